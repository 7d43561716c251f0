"""Running daemon requests from operators without freezing Blender.

An action is a list of :class:`Request` objects (prepared in Blender's main thread: the
meshes are converted up front) run by a :class:`Job` on one daemon connection, one request
after another. The job never blocks in :meth:`Job.tick`: it polls the client's
:class:`tessd.Job`, which a background reader thread feeds. Operators use it two ways:

- invoked from the UI: modal, a window-manager timer calls ``tick``; progress shows in the
  status bar and the window manager's progress cursor; Esc cancels (the daemon stops the
  request at its next checkpoint);
- called from a script (``EXEC_DEFAULT``): the same job is ticked to the end in place.

Blender data is created only after every request succeeded (``JobOperator.apply``), so an
error, a cancel or a missing daemon leave the scene as it was; the result is one undo step
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
        self.__dict__.update(extra)  # whatever apply() needs later (object names, ...)


class Job:
    """Runs requests in order on one connection; states RUNNING, DONE, FAILED, CANCELLED."""

    def __init__(self, requests, title="tessd"):
        self.requests = list(requests)
        self.title = title
        self.state = "READY"
        self.error = None               # message for FAILED
        self.cancel_requested = False
        self.cancelled_by_daemon = False  # the daemon answered `cancelled`
        self.ticks = 0
        self._client = None
        self._index = 0
        self._current = None
        self.timings = []  # (label, seconds from submit to reply) per request

    # -- driving ------------------------------------------------------------------------------

    def start(self, context=None):
        """Connects (starting the daemon if allowed) and sends the first request."""
        try:
            self._client = daemon.connect(context)
            self.state = "RUNNING"
            self._submit()
        except daemon.DaemonError as e:
            self._fail(str(e))
        except (tessd.DaemonUnavailable, OSError) as e:
            self._fail("lost the tessd daemon: %s" % e)
        return self.state == "RUNNING"

    def _submit(self):
        req = self.requests[self._index]
        self._t0 = time.perf_counter()
        self._current = self._client.submit(req.op, req.params, req.arrays)

    def tick(self):
        """Consumes what the daemon sent; returns True once the job has ended."""
        self.ticks += 1
        if self.state == "RUNNING":
            self._step()
        for hook in list(TICK_HOOKS):
            hook(self)
        return self.finished

    def _step(self):
        while self.state == "RUNNING" and self._current.poll():
            req = self.requests[self._index]
            try:
                req.result, req.arrays_out = self._current.result(0)
            except tessd.TessdError as e:
                if e.code == "cancelled":
                    self.cancelled_by_daemon = True
                    self._end("CANCELLED")
                else:
                    who = (" on %s" % req.label) if req.label else ""
                    self._fail("tessd %s%s failed (%s): %s" % (req.op, who, e.code, e.message))
                return
            except (tessd.DaemonUnavailable, OSError) as e:
                self._fail("lost the tessd daemon during %s: %s (did it crash? see its log next "
                           "to the socket)" % (req.op, e))
                return
            self.timings.append((req.label or req.op, time.perf_counter() - self._t0))
            req.arrays = None  # the input is no longer needed
            if self.cancel_requested:
                self._end("CANCELLED")
                return
            self._index += 1
            if self._index == len(self.requests):
                self._end("DONE")
                return
            try:
                self._submit()
            except (tessd.DaemonUnavailable, OSError) as e:
                self._fail("lost the tessd daemon: %s" % e)

    def wait(self, timeout=0.1):
        """Blocks up to ``timeout`` seconds for news (the script path)."""
        if self.state == "RUNNING" and self._current is not None:
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
    def finished(self):
        return self.state in ("DONE", "FAILED", "CANCELLED")

    @property
    def fraction(self):
        """Overall progress in [0, 1]."""
        if self.finished or not self.requests:
            return 1.0
        p = self._current.progress if self._current is not None else None
        within = p.fraction if p is not None else 0.0
        return (self._index + max(0.0, min(1.0, within))) / len(self.requests)

    @property
    def message(self):
        p = self._current.progress if (self._current is not None and not self.finished) else None
        req = self.requests[min(self._index, len(self.requests) - 1)] if self.requests else None
        parts = [self.title]
        if req is not None and req.label:
            parts.append(req.label)
        if p is not None and (p.stage or p.message):
            parts.append(" ".join(x for x in (p.stage, p.message) if x))
        return ": ".join(parts)

    def _fail(self, message):
        self.error = message
        self._end("FAILED")

    def _end(self, state):
        self.state = state
        self._current = None
        if self._client is not None:
            self._client.close()  # closing also cancels anything still running on it
            self._client = None


class JobOperator:
    """Mixin for the add-on's operators. Subclasses implement:

    - ``prepare(context) -> list[Request]`` (raise UserError for a problem to report),
    - ``apply(context, requests, created) -> str`` building the Blender data (a summary to
      report), registering each new data block with ``created.add(...)`` so that a failure
      half-way removes them again.

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

    def apply(self, context, requests):
        raise NotImplementedError

    # -- entry points ---------------------------------------------------------------------------

    def invoke(self, context, event):
        self._modal = context.window is not None
        if self.dialog:
            return context.window_manager.invoke_props_dialog(self, width=360)
        return self.execute(context)

    def execute(self, context):
        modal = getattr(self, "_modal", False)
        self._modal = False  # a redo from the "Adjust Last Operation" panel runs in place
        job = self._begin(context)
        if job is None:
            return {'CANCELLED'}
        if modal and context.window is not None:
            wm = context.window_manager
            self._timer = wm.event_timer_add(0.1, window=context.window)
            wm.modal_handler_add(self)
            wm.progress_begin(0, 100)
            self._show_progress(context)
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
            self._show_progress(context)
        return {'PASS_THROUGH'}

    # -- steps ----------------------------------------------------------------------------------

    def _begin(self, context):
        try:
            requests = self.prepare(context)
        except UserError as e:
            self.report({'ERROR'}, str(e))
            return None
        if not requests:
            self.report({'ERROR'}, "tessd: select at least one mesh object")
            return None
        self._job = Job(requests, self.title)
        if not self._job.start(context):
            self.report({'ERROR'}, "%s; the scene is unchanged" % self._job.error)
            return None
        return self._job

    def _show_progress(self, context):
        job = self._job
        context.window_manager.progress_update(int(100 * job.fraction))
        if context.workspace is not None:
            context.workspace.status_text_set("%s  %d%%  (Esc to cancel)"
                                              % (job.message, int(100 * job.fraction)))

    def _end(self, context):
        job = self._job
        if getattr(self, "_timer", None) is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
            context.window_manager.progress_end()
            if context.workspace is not None:
                context.workspace.status_text_set(None)
        if job.state == "CANCELLED":
            self.report({'WARNING'}, "%s: cancelled; the scene is unchanged" % self.title)
            return {'CANCELLED'}
        if job.state != "DONE":
            self.report({'ERROR'}, "%s; the scene is unchanged" % job.error)
            return {'CANCELLED'}
        created = _Created()
        try:
            summary = self.apply(context, job.requests, created)
        except UserError as e:
            created.remove()
            self.report({'ERROR'}, "%s; the scene is unchanged" % e)
            return {'CANCELLED'}
        except Exception as e:
            created.remove()
            self.report({'ERROR'}, "%s: could not build the result (%s: %s); the scene is "
                                   "unchanged" % (self.title, type(e).__name__, e))
            return {'CANCELLED'}
        if summary:
            self.report({'INFO'}, summary)
        return {'FINISHED'}


class _Created:
    """The data blocks an apply() created, removed again if it fails half-way."""

    def __init__(self):
        self.ids = []

    def add(self, block):
        self.ids.append(block)
        return block

    def remove(self):
        for block in reversed(self.ids):
            try:
                if isinstance(block, bpy.types.Object):
                    bpy.data.objects.remove(block)
                elif isinstance(block, bpy.types.Mesh):
                    bpy.data.meshes.remove(block)
                elif isinstance(block, bpy.types.Collection):
                    bpy.data.collections.remove(block)
                elif isinstance(block, bpy.types.CacheFile):
                    bpy.data.cache_files.remove(block)
            except ReferenceError:
                pass
        self.ids.clear()
