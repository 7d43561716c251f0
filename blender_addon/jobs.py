"""Running daemon requests from operators without freezing Blender.

An action is a list of :class:`Task` objects, one per object (or per mesh that several
selected objects share). A task is converted to the protocol's arrays only when its turn
comes, from the job's tick, so Blender holds one object's arrays at a time, and a long
conversion (an animation baked frame by frame) advances a little per tick with progress and
Esc. Then its :class:`Request` objects run one after another on one daemon connection; the
job never blocks in :meth:`Job.tick`: it polls the client's :class:`tessd.Job`, which a
background reader thread feeds.

A task that fails (the object cannot be sent, the daemon refuses its mesh, it is already
below the target) is skipped with its reason and the others go on; the operator reports the
skipped ones in one warning. A lost daemon or a cancel ends the whole job.

Operators use jobs two ways:

- invoked from the UI: modal, a window-manager timer calls ``tick``; progress shows as a bar
  in the status bar (the mouse pointer stays the user's); Esc cancels (the daemon stops the
  request at its next checkpoint), and so does Blender cancelling the operator (a file load,
  the window closing);
- called from a script (``EXEC_DEFAULT``): the same job is ticked to the end in place.

Blender data is created only after the job ended (``JobOperator.apply_task``), so an error, a
cancel or a missing daemon leave the scene as it was; the result is one undo step
(``bl_options = {'REGISTER', 'UNDO'}``).

``TICK_HOOKS`` lets scripts and tests watch or cancel a job: each hook is called as
``hook(job)`` after every tick (headless Blender has no event loop, so this is how a test
cancels a job mid-way through the same code path as Esc).
"""

import time

import bpy

from . import daemon
from .client import tessd

#: Callables ``hook(job)`` run after every tick of every job.
TICK_HOOKS = []
#: Seconds of conversion work one tick may do before handing control back to Blender.
TICK_BUDGET = 0.05
#: Seconds between the ticks of a modal job: a reply is taken up to this long after it came
#: (issue 33: part of what the user waits for; a tick with nothing new costs microseconds).
TICK_INTERVAL = 0.02
#: Seconds between redraws of the status bar's progress while a modal job runs.
REDRAW_INTERVAL = 0.1
#: Jobs running modally, drawn in the status bar.
_RUNNING = []


class UserError(Exception):
    """A problem to report to the user as it is (nothing sent to the daemon yet)."""


class Request:
    """One daemon call: ``op``, ``params``, ``arrays``; ``label`` names it in messages
    (e.g. the object). After the job, ``result`` and ``arrays_out`` hold the reply."""

    def __init__(self, op, params, arrays=None, label="", **extra):
        self.op = op
        self.params = params
        self.arrays = arrays
        self.label = label
        self.result = None
        self.arrays_out = None
        self.__dict__.update(extra)  # whatever apply needs later (object names, ...)


class Task:
    """One object, or the objects sharing one mesh: ``steps`` is a generator that yields
    progress fractions while it converts and returns the task's requests (raising
    UserError when the object cannot be sent). ``error`` says why a task was skipped."""

    def __init__(self, label, steps, **extra):
        self.label = label
        self.steps = steps
        self.requests = []
        self.error = None
        self.__dict__.update(extra)

    @property
    def ok(self):
        return self.error is None

    def request(self, op):
        """The first request of ``op`` (or None)."""
        return next((r for r in self.requests if r.op == op), None)


def skipped_task(label, why):
    """A task that is reported as skipped without running (an instance, linked data)."""
    task = Task(label, iter(()))
    task.error = why
    return task


class Job:
    """Runs tasks in order on one connection; states READY, RUNNING, DONE, FAILED,
    CANCELLED. DONE means at least one task finished; ``skipped`` lists the others."""

    def __init__(self, tasks, title="tessd"):
        self.tasks = list(tasks)
        self.title = title
        self.state = "READY"
        self.error = None               # message for FAILED
        self.cancel_requested = False
        self.cancelled_by_daemon = False  # the daemon answered `cancelled`
        self.ticks = 0
        self.warnings = []              # from the connection (e.g. a shared old daemon)
        self.daemon_problem = False     # FAILED, and the fix is in the add-on's preferences
        self._client = None
        self._task = 0
        self._req = 0
        self._current = None
        self._preparing = False
        self._prep_fraction = 0.0
        self.timings = []  # (label, seconds from submit to reply) per request

    # -- driving ------------------------------------------------------------------------------

    def start(self, context=None):
        """Connects (starting the daemon if allowed) and begins the first task."""
        try:
            self._client = daemon.connect(context)
            self.warnings.extend(getattr(self._client, "tessd_warnings", []))
            self.state = "RUNNING"
            self._begin_task()
        except daemon.DaemonError as e:
            self.daemon_problem = bool(getattr(e, "offer_preferences", False))
            self._fail(str(e))
        except (tessd.DaemonUnavailable, OSError) as e:
            self._fail("lost the tessd daemon: %s" % e)
        return self.state == "RUNNING"

    def tick(self):
        """Does a slice of work and consumes what the daemon sent; True once the job ended."""
        self.ticks += 1
        if self.state == "RUNNING":
            try:
                self._step()
            except (tessd.DaemonUnavailable, OSError) as e:
                self._fail("lost the tessd daemon: %s (did it crash? see its log next to the "
                           "socket)" % e)
        for hook in list(TICK_HOOKS):
            hook(self)
        return self.finished

    def _begin_task(self):
        """Moves to the next task that is not done, or ends the job."""
        while self._task < len(self.tasks) and not self.tasks[self._task].ok:
            self._task += 1  # skipped before it started (e.g. an instance, linked data)
        if self._task < len(self.tasks):
            self._preparing, self._prep_fraction, self._req = True, 0.0, 0
        elif any(t.ok for t in self.tasks):
            self._end("DONE")
        else:
            self._fail("%s: %s" % (self.title, "; ".join(
                "%s: %s" % (t.label, t.error) if t.label else t.error for t in self.tasks)))

    def _skip(self, message):
        """The current task failed: record why and go on with the next."""
        self.tasks[self._task].error = message
        self._current = None
        self._task += 1
        self._begin_task()

    def _step(self):
        deadline = time.perf_counter() + TICK_BUDGET
        while self.state == "RUNNING":
            # A request in flight ends with the daemon's answer (`cancelled` once it saw the
            # cancel); otherwise a cancel takes effect at once.
            if self.cancel_requested and (self._preparing or self._current is None):
                self._end("CANCELLED")
                return
            task = self.tasks[self._task]
            if self._preparing:
                if not self._prepare(task, deadline):
                    return
                continue
            if not self._current.poll():
                return
            if not self._receive(task):
                continue
            if self.cancel_requested:
                self._end("CANCELLED")
                return
            self._req += 1
            if self._req < len(task.requests):
                self._submit(task)
            else:
                self._task += 1
                self._begin_task()

    def _prepare(self, task, deadline):
        """Advances the task's conversion; True once its first request is sent."""
        try:
            while True:
                self._prep_fraction = float(next(task.steps) or 0.0)
                if time.perf_counter() > deadline:
                    return False
        except StopIteration as stop:
            task.requests = list(stop.value or [])
        except UserError as e:
            self._skip(str(e))
            return False
        except (tessd.DaemonUnavailable, OSError):
            raise
        except Exception as e:  # a conversion bug must not take the batch (or Blender) down
            self._skip("could not be converted (%s: %s)" % (type(e).__name__, e))
            return False
        self._preparing = False
        if not task.requests:
            self._skip("nothing to send")
            return False
        self._submit(task)
        return True

    def _submit(self, task):
        req = task.requests[self._req]
        self._t0 = time.perf_counter()
        self._current = self._client.submit(req.op, req.params, req.arrays)

    def _receive(self, task):
        """Takes the current request's reply; False when the task was skipped or the job
        ended."""
        req = task.requests[self._req]
        try:
            req.result, req.arrays_out = self._current.result(0)
        except tessd.TessdError as e:
            if e.code == "cancelled":
                self.cancelled_by_daemon = True
                self._end("CANCELLED")
            else:
                self._skip("%s failed (%s): %s" % (req.op, e.code, e.message))
            return False
        self.timings.append((req.label or req.op, time.perf_counter() - self._t0))
        req.arrays = None  # the input is no longer needed
        return True

    def wait(self, timeout=0.1):
        """Blocks up to ``timeout`` seconds for news (the script path)."""
        if self.state == "RUNNING" and self._current is not None and not self._preparing:
            self._current.wait(timeout)

    def run(self, context=None):
        """Starts (if needed) and ticks to the end; returns the final state."""
        if self.state == "READY":
            self.start(context)
        while not self.tick():
            self.wait(0.1)
        return self.state

    def cancel(self):
        """Asks the daemon to stop; the job ends CANCELLED at a later tick."""
        self.cancel_requested = True
        if self.state == "RUNNING" and self._current is not None:
            self._current.cancel()
        elif self.state == "READY":
            self._end("CANCELLED")

    # -- state --------------------------------------------------------------------------------

    @property
    def requests(self):
        return [r for t in self.tasks for r in t.requests]

    @property
    def skipped(self):
        return [t for t in self.tasks if not t.ok]

    @property
    def finished(self):
        return self.state in ("DONE", "FAILED", "CANCELLED")

    @property
    def fraction(self):
        """Overall progress in [0, 1]: a tenth of each task for its conversion."""
        if self.finished or not self.tasks:
            return 1.0
        task = self.tasks[min(self._task, len(self.tasks) - 1)]
        if self._preparing:
            within = 0.1 * max(0.0, min(1.0, self._prep_fraction))
        else:
            p = self._current.progress if self._current is not None else None
            part = max(0.0, min(1.0, p.fraction)) if p is not None else 0.0
            within = 0.1 + 0.9 * (self._req + part) / max(1, len(task.requests))
        return (self._task + within) / len(self.tasks)

    @property
    def message(self):
        parts = [self.title]
        if self.finished or not self.tasks:
            return parts[0]
        task = self.tasks[min(self._task, len(self.tasks) - 1)]
        if len(self.tasks) > 1:
            parts.append("%d/%d %s" % (self._task + 1, len(self.tasks), task.label))
        elif task.label:
            parts.append(task.label)
        if self._preparing:
            parts.append("preparing")
        else:
            p = self._current.progress if self._current is not None else None
            if p is not None and (p.stage or p.message):
                parts.append(" ".join(x for x in (p.stage, p.message) if x))
        return ": ".join(parts)

    def _fail(self, message):
        self.error = message
        self._end("FAILED")

    def _end(self, state):
        self.state = state
        self._current = None
        if self._preparing and self._task < len(self.tasks):
            self.tasks[self._task].steps.close()  # runs the conversion's cleanup
            self._preparing = False
        if self._client is not None:
            self._client.close()  # closing also cancels anything still running on it
            self._client = None


class JobOperator:
    """Mixin for the add-on's operators. Subclasses implement:

    - ``prepare(context) -> list[Task]`` (cheap: conversion happens in the tasks' steps;
      raise UserError for a problem with the whole action),
    - ``apply_task(context, task, created) -> list[Object]`` building the Blender data of one
      finished task, registering each new data block with ``created.add(...)`` and queuing
      mesh swaps with ``created.swap(obj, mesh)``; a UserError skips that task alone,
    - optionally ``finish(context, tasks, results)`` (after all tasks, e.g. an assembly
      file) and ``summary(context, tasks) -> str`` (the INFO report).

    ``invoke`` shows ``dialog`` (if the class asks for one), then runs modal; ``execute``
    alone (scripts, redo) runs to completion.
    """

    bl_options = {'REGISTER', 'UNDO'}
    dialog = True
    title = "tessd"

    @classmethod
    def poll(cls, context):
        return context.mode == 'OBJECT'

    def prepare(self, context):
        raise NotImplementedError

    def apply_task(self, context, task, created):
        raise NotImplementedError

    def finish(self, context, tasks, results):
        pass

    def summary(self, context, tasks):
        return ""

    # -- entry points ---------------------------------------------------------------------------

    def invoke(self, context, event):
        self._modal = context.window is not None
        if self.dialog:
            return context.window_manager.invoke_props_dialog(self, width=380)
        return self.execute(context)

    def execute(self, context):
        modal = getattr(self, "_modal", False)
        self._modal = False  # a redo from the "Adjust Last Operation" panel runs in place
        job = self._begin(context)
        if job is None:
            return {'CANCELLED'}
        if modal and context.window is not None:
            # The first slice at once (the conversion starts and, when it is quick, the
            # request goes out now), then one per timer event.
            if job.tick():
                return self._end(context)
            wm = context.window_manager
            self._timer = wm.event_timer_add(TICK_INTERVAL, window=context.window)
            wm.modal_handler_add(self)
            _RUNNING.append(job)
            self._redrawn = time.perf_counter()
            _redraw_status(context)
            return {'RUNNING_MODAL'}
        job.run(context)
        return self._end(context)

    def modal(self, context, event):
        job = self._job
        if event.type == 'ESC' and event.value == 'PRESS':
            job.cancel()
            return {'RUNNING_MODAL'}
        if event.type == 'TIMER' and event.timer is self._timer:
            if job.tick():
                return self._end(context)
            now = time.perf_counter()
            if now - self._redrawn >= REDRAW_INTERVAL:
                self._redrawn = now
                _redraw_status(context)
        return {'PASS_THROUGH'}

    def cancel(self, context):
        """Blender cancels the operator (a file is loaded, the window closes): stop the job
        and leave the scene alone."""
        job = getattr(self, "_job", None)
        if job is not None and not job.finished:
            job.cancel()
            job._end("CANCELLED")
        self._stop_modal(context)

    # -- steps ----------------------------------------------------------------------------------

    def _begin(self, context):
        try:
            tasks = self.prepare(context)
        except UserError as e:
            self.report({'ERROR'}, str(e))
            return None
        if not tasks:
            self.report({'ERROR'}, "tessd: select at least one mesh object")
            return None
        self._job = Job(tasks, self.title)
        if not self._job.start(context):
            self._report_failure(context, "%s; the scene is unchanged" % self._job.error)
            return None
        return self._job

    def _report_failure(self, context, message):
        self.report({'ERROR'}, message)
        offer = getattr(daemon, "offer_preferences", None)
        if offer is not None and self._job.daemon_problem:
            offer(context, message)

    def _stop_modal(self, context):
        job = getattr(self, "_job", None)
        if job in _RUNNING:
            _RUNNING.remove(job)
        if getattr(self, "_timer", None) is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        _redraw_status(context)

    def _end(self, context):
        job = self._job
        self._stop_modal(context)
        for w in job.warnings:
            self.report({'WARNING'}, w)
        if job.state == "CANCELLED":
            self.report({'WARNING'}, "%s: cancelled; the scene is unchanged" % self.title)
            return {'CANCELLED'}
        if job.state != "DONE":
            self.report({'ERROR'}, "%s; the scene is unchanged" % job.error)
            return {'CANCELLED'}
        results, done, swaps = [], [], []
        for task in (t for t in job.tasks if t.ok):
            created = _Created()
            try:
                results += self.apply_task(context, task, created) or []
            except UserError as e:
                created.remove()
                task.error = str(e)
                continue
            except Exception as e:
                created.remove()
                task.error = "could not build the result (%s: %s)" % (type(e).__name__, e)
                continue
            swaps += created.swaps
            done.append(task)
        if not done:
            self.report({'ERROR'}, "%s: %s; the scene is unchanged" % (
                self.title, "; ".join("%s: %s" % (t.label, t.error) for t in job.tasks)))
            return {'CANCELLED'}
        for obj, mesh in swaps:  # last: nothing can fail after the scene's objects change
            obj.data = mesh
        self.finish(context, done, results)
        select_only(context, results)
        skipped = [t for t in job.tasks if not t.ok]
        if skipped:
            self.report({'WARNING'}, "%s: skipped %d of %d: %s" % (
                self.title, len(skipped), len(job.tasks),
                "; ".join("%s: %s" % (t.label, t.error) for t in skipped)))
        text = self.summary(context, done)
        if text:
            self.report({'INFO'}, text)
        return {'FINISHED'}


def select_only(context, objects):
    for o in context.selected_objects:
        o.select_set(False)
    for o in objects:
        try:
            o.select_set(True)
        except RuntimeError:  # not in the view layer (e.g. excluded collection)
            pass
    if objects:
        try:
            context.view_layer.objects.active = objects[0]
        except (RuntimeError, TypeError):
            pass


class _Created:
    """The data blocks an apply created, removed again if it fails half-way, and the mesh
    swaps it queued for when nothing can fail any more."""

    def __init__(self):
        self.ids = []
        self.swaps = []

    def add(self, block):
        self.ids.append(block)
        return block

    def swap(self, obj, mesh):
        self.swaps.append((obj, mesh))

    def remove(self):
        for block in reversed(self.ids):
            try:
                bpy.data.batch_remove([block])  # any kind of data block (objects, meshes, ...)
            except ReferenceError:
                pass
        self.ids.clear()
        self.swaps.clear()


# -- the status bar ---------------------------------------------------------------------------

def _draw_status(self, context):
    for job in list(_RUNNING):
        row = self.layout.row(align=True)
        row.progress(factor=job.fraction, type='BAR',
                     text="%s  %d%%" % (job.message, int(100 * job.fraction)))
        row.label(text="Esc to cancel")


def _redraw_status(context):
    screen = getattr(context, "screen", None)
    for area in (screen.areas if screen is not None else ()):
        if area.type == 'STATUSBAR':
            area.tag_redraw()


def register():
    bpy.types.STATUSBAR_HT_header.append(_draw_status)


def unregister():
    bpy.types.STATUSBAR_HT_header.remove(_draw_status)
    _RUNNING.clear()
