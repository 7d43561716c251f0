"""The three phases every workbench operation goes through, and what they share.

A command must not freeze FreeCAD while the daemon works, and FreeCAD's documents may only be
touched from the GUI thread. So each operation is a :class:`Task` in three phases:

1. ``prepare_<op>(...)`` (api.py) reads the document on the GUI thread, quickly: shapes,
   meshes, labels, placements, colours (shapes.py), and returns the task;
2. :meth:`Task.run` does the work on any thread without touching a document: the B-Rep
   export, the daemon requests (with progress reports, and cancellation through a
   ``threading.Event``), building the result meshes and shapes, writing files;
3. :meth:`Task.apply` puts the results into the document on the GUI thread, in one undo
   transaction, and returns what the console function returns.

The console functions run the three in a row; the GUI runs phase 2 on a worker thread and
marshals the call of phase 3 back to the GUI thread.
"""

import threading
from typing import Any, Callable, Dict, List, Optional, Tuple

import FreeCAD
import tessd  # the client package (this package's __init__ made it importable)

from . import daemon_link

#: The client's error: an error reply from the daemon, its message as the daemon wrote it.
TessdError = tessd.TessdError

ProgressCallback = Callable[[float, str], None]

#: How often a running request looks at the cancel flag (seconds).
POLL_S = 0.05
#: How long a cancelled request may take to confirm before the task gives up on it (seconds;
#: the connection is closed then, which cancels whatever is left of it in the daemon).
CANCEL_WAIT_S = 2.0


class Cancelled(Exception):
    """The task was cancelled (its daemon request too); nothing was changed."""


class Task:
    """An operation prepared from the document, to be run off the GUI thread and applied.

    Subclasses set :attr:`title` and implement :meth:`_run` (given a connected client) and
    :meth:`_apply` (given the document, inside the transaction). :attr:`reports` holds the
    daemon's result per object (counts, errors reached, notes) for a UI to show; :attr:`warnings`
    what the user should be told.
    """

    #: The undo step's name and the progress title, e.g. "Tessellate".
    title = "tessd"
    #: Whether apply() adds document objects (then it opens a transaction and recomputes).
    changes_document = True

    def __init__(self, doc: Any = None):
        self.doc = doc
        self.reports: List[Dict[str, Any]] = []
        self.warnings: List[str] = []
        self._progress: Optional[ProgressCallback] = None
        self._cancel: Optional[threading.Event] = None
        self._ran = False
        self._created: List[str] = []
        #: The last daemon request (a tessd.Job), e.g. to read its outcome after a cancel.
        self.job: Optional["tessd.Job"] = None

    # -- phase 2 -------------------------------------------------------------------------

    def run(self, progress: Optional[ProgressCallback] = None,
            cancel: Optional[threading.Event] = None) -> None:
        """Does the work (any thread; no document access). ``progress(fraction, message)`` is
        called as the daemon reports; when ``cancel`` is set the running request is cancelled
        and :class:`Cancelled` raised. Daemon errors raise :class:`TessdError`."""
        self._progress, self._cancel = progress, cancel
        self._ran = False
        self.check_cancel()
        with daemon_link.client() as client:
            self._run(client)
        self.check_cancel()
        self.report(1.0, "done")
        self._ran = True

    def _run(self, client: "tessd.Client") -> None:
        raise NotImplementedError

    def cancelled(self) -> bool:
        return self._cancel is not None and self._cancel.is_set()

    def check_cancel(self) -> None:
        """Raises :class:`Cancelled` once the cancel flag is set (call it between steps)."""
        if self.cancelled():
            raise Cancelled("%s cancelled" % self.title)

    def report(self, fraction: float, message: str) -> None:
        if self._progress is not None:
            self._progress(min(max(float(fraction), 0.0), 1.0), message)

    def call(self, client: "tessd.Client", op: str, params: Dict[str, Any],
             arrays: Optional[Dict[str, Any]] = None, span: Tuple[float, float] = (0.0, 1.0),
             label: str = "") -> Tuple[Dict[str, Any], Dict[str, Any]]:
        """One daemon request, its progress mapped onto ``span`` of the task's, cancelled when
        the cancel flag is set. Returns ``(result, arrays)``."""
        job = self.submit(client, op, params, arrays, span, label)
        return self.wait(job, op, span, label)

    def submit(self, client: "tessd.Client", op: str, params: Dict[str, Any],
               arrays: Optional[Dict[str, Any]] = None, span: Tuple[float, float] = (0.0, 1.0),
               label: str = "") -> "tessd.Job":
        """Sends one daemon request without waiting for it (several may run at once: the
        daemon serves them in parallel); :meth:`wait` collects it."""
        self.check_cancel()
        lo, hi = span
        prefix = "%s: " % label if label else ""

        def on_progress(fraction: float, stage: str, message: str) -> None:
            self.report(lo + (hi - lo) * fraction, prefix + (message or stage or op))

        self.report(lo, prefix + op)
        job = client.submit(op, params, arrays, progress=on_progress)
        self.job = job
        return job

    def wait(self, job: "tessd.Job", op: str, span: Tuple[float, float] = (0.0, 1.0),
             label: str = "") -> Tuple[Dict[str, Any], Dict[str, Any]]:
        """The outcome of a submitted request: ``(result, arrays)``; when the cancel flag is
        set meanwhile, the request is cancelled and :class:`Cancelled` raised."""
        while not job.wait(POLL_S):
            if self.cancelled():
                job.cancel()
                job.wait(CANCEL_WAIT_S)
                raise Cancelled("%s cancelled" % self.title)
        try:
            result = job.result(0)
        except TessdError as e:
            if e.code == "cancelled" and self.cancelled():
                raise Cancelled("%s cancelled" % self.title) from None
            raise
        self.check_cancel()
        prefix = "%s: " % label if label else ""
        self.report(span[1], prefix + op + " done")
        return result

    # -- phase 3 -------------------------------------------------------------------------

    def apply(self, doc: Any = None) -> Any:
        """Puts the results into ``doc`` (default: the task's document, else the active one)
        in one transaction named :attr:`title`, recomputes, and returns the results (GUI
        thread). A failure aborts the transaction: the document is left as it was."""
        if not self._ran:
            raise RuntimeError("%s: run() has not completed; nothing to apply" % self.title)
        for w in self.warnings:
            FreeCAD.Console.PrintWarning("tessd: %s\n" % w)
        if not self.changes_document:
            return self._apply(None)
        doc = doc or self.doc or FreeCAD.ActiveDocument
        if doc is None:
            raise RuntimeError("%s: no document to add the results to" % self.title)
        self._created = []
        doc.openTransaction(self.title)
        try:
            result = self._apply(doc)
            doc.recompute()
        except BaseException:
            doc.abortTransaction()
            # Without undo (a console document's UndoMode is 0) aborting removes nothing.
            for name in reversed(self._created):
                if doc.getObject(name) is not None:
                    doc.removeObject(name)
            raise
        doc.commitTransaction()
        return result

    def _apply(self, doc: Any) -> Any:
        raise NotImplementedError

    def new_object(self, doc: Any, type_id: str, label: str) -> Any:
        """A new document object of ``type_id`` named and labelled ``label`` (FreeCAD makes the
        name an identifier and both unique), removed again if apply() fails."""
        obj = doc.addObject(type_id, label)
        obj.Label = label
        self._created.append(obj.Name)
        return obj


__all__ = ["Cancelled", "Task", "TessdError"]
