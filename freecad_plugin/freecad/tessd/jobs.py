"""Running an ``api`` task without freezing FreeCAD.

A command's task panel turns its fields into a task with ``api.prepare_<name>(...)`` on the
GUI thread (that reads the objects and nothing else), then hands it to :class:`Job`:

- ``task.run(progress, cancel)`` runs on a worker thread (``threading.Thread``): it talks to
  the daemon and never touches the document;
- the GUI thread polls the worker with a ``QTimer`` (every :data:`POLL_MS` ms): progress goes
  to the main window's status bar (a message, a ``QProgressBar`` and a Cancel button), so
  the GUI stays responsive and Qt widgets are only ever used from the GUI thread;
- when ``run`` returned, ``task.apply(doc)`` runs on the GUI thread: the one place the
  document changes, in one undo transaction (``api`` opens and commits it);
- Cancel sets the task's ``threading.Event``: ``run`` cancels the daemon job and raises
  ``api.Cancelled``; a job cancelled at any point before ``apply`` never applies, so the
  document stays as it was;
- an error (``api.TessdError`` carries the daemon's message) ends the job FAILED and, unless
  the caller asked for quiet (the Simplify panel's live preview), shows a critical message
  box with that message.

Scripts and tests drive the same path: ``job = Job(task).start()``, then ``job.wait(60)``
processes Qt events until it ended. :data:`FINISHED_HOOKS` are called as ``hook(job)`` when
any job ends.
"""

import threading
import time
import traceback

import FreeCAD

from . import api
from .qt import QtCore, QtWidgets

#: How often the GUI thread looks at a running worker, in milliseconds (fast enough for a
#: smooth progress bar, slow enough to cost nothing).
POLL_MS = 50
#: Callables ``hook(job)`` run on the GUI thread when a job ends, whatever its state.
FINISHED_HOOKS = []

RUNNING = "running"
DONE = "done"
FAILED = "failed"
CANCELLED = "cancelled"

_running = []  # the jobs started and not yet ended, so none is garbage-collected mid-way


def running():
    """The jobs that have started and not ended, oldest first."""
    return list(_running)


def main_window():
    """FreeCAD's main window, or None without the GUI (freecadcmd)."""
    if not FreeCAD.GuiUp:
        return None
    import FreeCADGui
    return FreeCADGui.getMainWindow()


def describe_error(error):
    """The message a user reads for ``error``: the daemon's own words for ``api.TessdError``
    (its ``message``, without the protocol code),
    the exception's text otherwise (its class name when the text is empty)."""
    if isinstance(error, api.TessdError):
        return (error.message or str(error)).strip() or "the tessd daemon reported an error"
    text = str(error).strip()
    return text if text else type(error).__name__


def show_error(title, message, details=None):
    """A critical message box over the main window. It is opened window-modal and returned at
    once (``open()``, not ``exec_()``), so no nested event loop waits on it: the GUI and any
    script that drives it keep running. The box deletes itself when closed."""
    FreeCAD.Console.PrintError("%s: %s\n" % (title, message))
    box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Critical, title, message,
                                QtWidgets.QMessageBox.Ok, main_window())
    box.setObjectName("tessdErrorBox")
    if details:
        box.setDetailedText(details)
    box.setAttribute(QtCore.Qt.WA_DeleteOnClose)
    box.open()
    return box


class StatusBarProgress:
    """A message, a progress bar and a Cancel button at the right of the status bar, for one
    job; ``remove()`` takes them away."""

    def __init__(self, title, on_cancel):
        self.title = title
        self.widget = QtWidgets.QWidget()
        self.widget.setObjectName("tessdProgress")
        layout = QtWidgets.QHBoxLayout(self.widget)
        layout.setContentsMargins(0, 0, 0, 0)
        self.label = QtWidgets.QLabel(title)
        self.bar = QtWidgets.QProgressBar()
        self.bar.setRange(0, 1000)
        self.bar.setMaximumWidth(180)
        self.bar.setTextVisible(False)
        self.cancel = QtWidgets.QPushButton("Cancel")
        self.cancel.setObjectName("tessdCancel")
        self.cancel.setToolTip("Stop this tessd job (the daemon stops it too); "
                               "the document is left as it was")
        self.cancel.clicked.connect(on_cancel)
        for w in (self.label, self.bar, self.cancel):
            layout.addWidget(w)
        self.status_bar = None
        window = main_window()
        if window is not None:
            self.status_bar = window.statusBar()
            self.status_bar.addPermanentWidget(self.widget)
            self.widget.show()

    def update(self, fraction, message):
        if fraction is None:
            self.bar.setRange(0, 0)  # busy indicator until the first fraction arrives
        else:
            self.bar.setRange(0, 1000)
            self.bar.setValue(int(round(1000 * min(max(fraction, 0.0), 1.0))))
        self.label.setText("%s: %s" % (self.title, message) if message else self.title)

    def cancelling(self):
        self.cancel.setEnabled(False)
        self.label.setText("%s: cancelling..." % self.title)

    def remove(self, final_message=None):
        if self.status_bar is not None:
            self.status_bar.removeWidget(self.widget)
            if final_message:
                self.status_bar.showMessage(final_message, 8000)
        self.widget.deleteLater()


class Job:
    """One ``api`` task: ``run`` on a worker thread, ``apply`` on the GUI thread.

    ``doc`` is given to ``apply`` (None: the task's own document). ``on_finished(job)`` is
    called on the GUI thread once the job ended. ``status=False`` shows nothing in the status
    bar and ``report_errors=False`` no message box (the live preview uses both). After the job
    ``state`` is DONE (``result`` holds what ``apply`` returned), FAILED (``error`` the
    message, ``exception`` the exception) or CANCELLED.
    """

    def __init__(self, task, doc=None, on_finished=None, status=True, report_errors=True):
        self.task = task
        self.doc = doc
        self.title = getattr(task, "title", "tessd")
        self.on_finished = on_finished
        self.cancel_event = threading.Event()
        self.state = None
        self.result = None
        self.error = None
        self.exception = None
        self.run_outcome = None  # how run() ended: "ran", "cancelled" (api.Cancelled), "error"
        self._trace = None
        self.seconds = None  # from start to the end of apply
        self._status = status
        self._report_errors = report_errors
        self._progress = (None, "")      # written by the worker, read by the GUI thread
        self._outcome = None             # ("ran",) / ("cancelled",) / ("error", exc, tb)
        self._lock = threading.Lock()
        self._thread = None
        self._timer = None
        self._bar = None
        self._started = None

    # -- GUI thread -----------------------------------------------------------------------------

    def start(self):
        """Starts the worker and the poll timer; returns self."""
        self.state = RUNNING
        self._started = time.monotonic()
        _running.append(self)
        if self._status:
            self._bar = StatusBarProgress(self.title, self.cancel)
            self._bar.update(None, "starting")
        self._thread = threading.Thread(target=self._work, name="tessd: " + self.title,
                                        daemon=True)
        self._thread.start()
        self._timer = QtCore.QTimer()
        self._timer.setInterval(POLL_MS)
        self._timer.timeout.connect(self._poll)
        self._timer.start()
        return self

    def cancel(self):
        """Asks the task to stop (it raises ``api.Cancelled`` at its next check, and the daemon
        job is cancelled); the job ends CANCELLED and nothing is applied."""
        if self.state != RUNNING or self.cancel_event.is_set():
            return
        self.cancel_event.set()
        if self._bar is not None:
            self._bar.cancelling()

    @property
    def done(self):
        return self.state in (DONE, FAILED, CANCELLED)

    def wait(self, timeout=None):
        """Processes Qt events until the job ended (True) or ``timeout`` seconds passed
        (False). For scripts and tests; the GUI itself never waits."""
        end = None if timeout is None else time.monotonic() + timeout
        app = QtWidgets.QApplication.instance()
        while not self.done:
            if end is not None and time.monotonic() > end:
                return False
            if app is not None:
                app.processEvents(QtCore.QEventLoop.AllEvents, 20)
            time.sleep(0.005)
            if app is None:
                self._poll()
        return True

    def _poll(self):
        with self._lock:
            fraction, message = self._progress
            outcome = self._outcome
        if outcome is None:
            if self._bar is not None and not self.cancel_event.is_set():
                self._bar.update(fraction, message)
            return
        self._timer.stop()
        self._thread.join()
        self.run_outcome = outcome[0]
        if outcome[0] == "ran" and not self.cancel_event.is_set():
            try:
                self.result = self.task.apply(self.doc)
                self.state = DONE
            except Exception as e:  # the document refused the result: same report as run's
                self._failed(e, traceback.format_exc())
        elif outcome[0] == "error" and not self.cancel_event.is_set():
            self._failed(outcome[1], outcome[2])
        else:
            self.state = CANCELLED
        self._finish()

    def _failed(self, exception, trace):
        self.state = FAILED
        self.exception = exception
        self.error = describe_error(exception)
        self._trace = trace

    def _finish(self):
        self.seconds = time.monotonic() - self._started
        if self._bar is not None:
            final = {DONE: "%s: done in %.1f s" % (self.title, self.seconds),
                     CANCELLED: "%s: cancelled, nothing changed" % self.title,
                     FAILED: "%s: failed" % self.title}[self.state]
            self._bar.remove(final)
            self._bar = None
        if self in _running:
            _running.remove(self)
        if self.state == FAILED and self._report_errors:
            details = None if isinstance(self.exception, api.TessdError) else self._trace
            show_error("tessd: " + self.title, self.error, details)
        for hook in [self.on_finished] + list(FINISHED_HOOKS):
            if hook is None:
                continue
            try:
                hook(self)
            except Exception:
                FreeCAD.Console.PrintError("tessd: %s\n" % traceback.format_exc())

    # -- worker thread --------------------------------------------------------------------------

    def _report(self, fraction, message=""):
        with self._lock:
            self._progress = (fraction, message or "")

    def _work(self):
        try:
            self.task.run(progress=self._report, cancel=self.cancel_event)
            outcome = ("ran",)
        except api.Cancelled:
            outcome = ("cancelled",)
        except BaseException as e:  # reported on the GUI thread, never lost with the thread
            outcome = ("error", e, traceback.format_exc())
        with self._lock:
            self._outcome = outcome
