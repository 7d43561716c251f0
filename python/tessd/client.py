"""The client: requests, replies, progress and cancellation over one daemon connection.

A :class:`Client` owns one connection and one background reader thread. The reader reads
every frame the daemon sends and routes it by request id to its :class:`Job`; jobs keep their
frames until the caller polls or waits. So one client can carry several requests at once and
be used from several threads, and a GUI can poll jobs from a timer without ever blocking.

    with Client() as c:
        result, arrays = c.call("mesh.stats", {"input": "bunny.ply"})  # relative to os.getcwd()
        job = c.submit("mesh.convert", {"input": "a.obj", "output": "a.ply"})
        while not job.poll():          # e.g. from a Blender timer
            print(job.progress)
        result, _ = job.result()

What the client does to a request before sending it:

- File paths in ``params`` (:data:`PATH_PARAMS`: ``input``, ``output``, ``a``, ``b``, ...) are
  made absolute against the caller's working folder (the daemon runs in its own folder, so a
  relative path would name another file there). ``os.PathLike`` values are accepted.
- Integer mesh arrays (``face_indices``, ``face_sizes``, ``*_indices``, ``crease_edges``,
  ``face_groups``, ``sharp_edges``) of another integer type are sent as the u32 the daemon
  reads (:func:`tessd.mesh_arrays.prepare_arrays`), so numpy's default int64 works; an array
  whose values do not fit is refused before anything is sent, with a :class:`TessdError`
  (code ``invalid_mesh``, also a ``ValueError``) naming the array, the value and why. Float
  arrays and other names go as given (``debug.echo``'s arrays too).

Timeouts: ``Client(timeout=T)`` bounds connecting to the socket (:class:`DaemonUnavailable`
after T seconds) and is the default timeout of every :meth:`Client.call` (and of ``ping`` and
``hello``), which bounds the wait for the reply, counted from when the request has been sent:
when it passes, the call sends a ``cancel`` for the request and raises :class:`CallTimeout`.
``call(..., timeout=S)`` sets one call's own bound, ``timeout=None`` waits as long as the
request runs. Writing the request is not bounded (the daemon reads requests as they come).
:meth:`Client.submit` never waits; :meth:`Job.result` and :meth:`Job.wait` take their own
timeout (default: none).
"""

from __future__ import annotations

import collections
import itertools
import os
import threading
import time
import weakref
from typing import Any, Callable, Deque, Dict, List, Mapping, NamedTuple, Optional, Tuple

from .errors import CallTimeout, Error
from .frame import ArraysArg, ProtocolError, encode_frame, read_frame
from .mesh_arrays import prepare_arrays
from .socket_path import resolve_socket
from .transport import DaemonUnavailable, connect

#: Default largest payload the client accepts in a reply (64 GiB): guards against garbage.
DEFAULT_CLIENT_MAX_PAYLOAD = 64 * 1024 ** 3

ProgressCallback = Callable[[float, str, str], Optional[bool]]

#: The parameters of each operation that name files (docs/protocol.md): the client makes them
#: absolute against its working folder before sending. A list (``render``'s ``input``) has each
#: string item made absolute; values that are not strings or paths (``per_level: true``) are
#: left alone.
PATH_PARAMS: Dict[str, Tuple[str, ...]] = {
    "mesh.stats": ("input",),
    "mesh.convert": ("input", "output"),
    "simplify": ("input", "output", "partition_output"),
    "lod": ("input", "output", "per_level"),
    "subdivide": ("input", "output"),
    "compare": ("a", "b"),
    "brep.load": ("input",),
    "tessellate": ("input", "output"),
    "trim.classify": ("input",),
    "render": ("input", "output", "face_ids"),
    "codec.compress": ("input", "output"),
    "codec.decompress": ("input", "output"),
    "codec.view": ("input", "output"),
}

#: Operations whose arrays are sent exactly as given (no dtype conversion).
RAW_ARRAY_OPS = frozenset({"debug.echo"})

#: The default of :meth:`Client.call`'s ``timeout``: the client's own.
_CLIENT_TIMEOUT: Any = object()


def _absolute(value: Any) -> Any:
    """``value`` made absolute when it is a non-empty path (str or os.PathLike), a list of
    them item by item; anything else unchanged."""
    if isinstance(value, list):
        return [_absolute(v) for v in value]
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
        if isinstance(value, bytes):
            value = os.fsdecode(value)
    if isinstance(value, str) and value and not os.path.isabs(value):
        # join, not abspath: `..` is left to the filesystem (a symbolic link's parent).
        return os.path.join(os.getcwd(), value)
    return value


def absolute_paths(op: str, params: Mapping[str, Any]) -> Dict[str, Any]:
    """A copy of ``params`` with the file paths of ``op`` (:data:`PATH_PARAMS`) absolute,
    resolved against the current working folder; other values are untouched."""
    out = dict(params)
    for key in PATH_PARAMS.get(op, ()):
        if key in out:
            out[key] = _absolute(out[key])
    return out


class TessdError(Error):
    """An error reply from the daemon (or the client's equivalent, e.g. ``cancelled``).

    ``code`` is one of the protocol's stable codes (``invalid_request``, ``invalid_mesh``,
    ``io``, ``cancelled``, ...); ``message`` is the daemon's human-readable text. A
    :class:`tessd.Error`.
    """

    def __init__(self, code: str, message: str, id: Optional[int] = None,
                 details: Optional[Mapping[str, Any]] = None):
        super().__init__("%s: %s" % (code, message))
        self.code = code
        self.message = message
        self.id = id
        self.details = dict(details or {})


class _ArrayRefused(TessdError, ValueError):
    """An array the client refuses before sending (code ``invalid_mesh``): a TessdError, as
    the daemon's answer would be, and a ValueError, as a bad argument."""


class _InvalidReply(ProtocolError, TessdError):
    """Bytes from the daemon's side that are no valid frame (e.g. another program listens on
    the socket): a :class:`ProtocolError`, and a :class:`TessdError` (code ``invalid_frame``
    or ``too_large``) as earlier versions raised."""

    def __init__(self, message: str, code: str = "invalid_frame"):
        TessdError.__init__(self, code, message)


class Progress(NamedTuple):
    """The latest progress a job reported."""

    fraction: float
    stage: str
    message: str


def _error_from_frame(message: Mapping[str, Any]) -> TessdError:
    err = message.get("error")
    if not isinstance(err, dict):
        return TessdError("internal", "error reply without an error object: %r" % (message,),
                          message.get("id"))
    return TessdError(str(err.get("code", "internal")), str(err.get("message", "")),
                      message.get("id"), err)


def _fresh(error: BaseException) -> BaseException:
    """A new exception like ``error`` (one shared instance raised in many threads would pile
    up tracebacks)."""
    if isinstance(error, _InvalidReply):
        return _InvalidReply(error.message, error.code)
    if isinstance(error, TessdError):
        return TessdError(error.code, error.message, error.id, error.details)
    if isinstance(error, DaemonUnavailable):
        return DaemonUnavailable(str(error))
    return error


_FRAME = "frame"
_FAIL = "fail"


class Job:
    """One request in flight. Created by :meth:`Client.submit`.

    Frames are queued by the client's reader thread; :meth:`poll`, :attr:`done`,
    :attr:`progress` and :meth:`result` consume them in the calling thread (which is also
    where the optional progress callback runs).
    """

    def __init__(self, client: "Client", id: int, op: str,
                 progress: Optional[ProgressCallback] = None):
        self.id = id
        self.op = op
        self._client = client
        self._callback = progress
        self._cond = threading.Condition()
        self._inbox: Deque[Tuple[Any, ...]] = collections.deque()
        self._done = False
        self._progress: Optional[Progress] = None
        self._result: Optional[Dict[str, Any]] = None
        self._arrays: Dict[str, Any] = {}
        self._files: List[str] = []
        self._error: Optional[BaseException] = None
        self._cancel_sent = False
        #: Milliseconds the daemon spent on the operation (from its reply), once done.
        self.elapsed_ms: Optional[float] = None

    # -- called by the reader thread --------------------------------------------------------

    def _push(self, item: Tuple[Any, ...]) -> None:
        with self._cond:
            self._inbox.append(item)
            self._cond.notify_all()

    # -- consumption ---------------------------------------------------------------------

    def _apply(self, item: Tuple[Any, ...]) -> Optional[Progress]:
        """Applies one queued item (lock held). Returns a Progress to report, if any."""
        if self._done:
            return None
        if item[0] == _FAIL:
            self._error = _fresh(item[1])
            self._done = True
            return None
        message, arrays = item[1], item[2]
        kind = message.get("type")
        if kind == "progress":
            p = message.get("progress") or {}
            try:
                fraction = float(p.get("fraction", 0.0))
            except (TypeError, ValueError):
                fraction = 0.0
            self._progress = Progress(fraction, str(p.get("stage", "")), str(p.get("message", "")))
            return self._progress
        self._done = True
        if kind == "ok":
            if self._cancel_sent:
                self._error = TessdError(
                    "cancelled", "cancelled by the client (the request had already finished)",
                    self.id)
            else:
                result = message.get("result")
                self._result = result if isinstance(result, dict) else {"value": result}
                self._arrays = arrays
                elapsed = message.get("elapsed_ms")
                self.elapsed_ms = float(elapsed) if isinstance(elapsed, (int, float)) else None
                files = message.get("files")
                self._files = list(files) if isinstance(files, list) else []
        elif kind == "error":
            self._error = _error_from_frame(message)
        else:
            self._error = TessdError("internal", "reply of unknown type %r" % (kind,), self.id)
        return None

    def _next(self, timeout: Optional[float]) -> Tuple[bool, Optional[Progress]]:
        """Waits up to ``timeout`` for one item and applies it: ``(got_one, progress)``."""
        with self._cond:
            if not self._inbox and not self._done and timeout != 0:
                self._cond.wait_for(lambda: self._inbox or self._done, timeout)
            if not self._inbox:
                return False, None
            return True, self._apply(self._inbox.popleft())

    def _report(self, progress: Optional[Progress]) -> None:
        if progress is not None and self._callback is not None:
            if self._callback(*progress) is False:
                self.cancel()

    def poll(self) -> bool:
        """Consumes every reply received so far, without blocking; returns :attr:`done`.

        Runs the progress callback (if :meth:`Client.submit` got one) for each progress frame;
        a callback returning ``False`` cancels the job.
        """
        while True:
            got, progress = self._next(0)
            if not got:
                return self._done
            self._report(progress)

    @property
    def done(self) -> bool:
        """Whether the final reply (ok or error) has arrived (polls first)."""
        return self.poll()

    @property
    def progress(self) -> Optional[Progress]:
        """The latest :class:`Progress` ``(fraction, stage, message)``, or None (polls first)."""
        self.poll()
        return self._progress

    @property
    def files(self) -> List[str]:
        """Paths the request wrote (from the ``ok`` reply)."""
        self.poll()
        return list(self._files)

    def wait(self, timeout: Optional[float] = None) -> bool:
        """Blocks until the job is done or ``timeout`` seconds pass; returns :attr:`done`."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.poll():
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                return False
            got, progress = self._next(remaining)
            self._report(progress)
        return True

    def result(self, timeout: Optional[float] = None) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        """Waits for the final reply and returns ``(result, arrays)``.

        Raises :class:`TessdError` for an error reply (code ``cancelled`` after a cancel),
        :class:`DaemonUnavailable` if the connection was lost, :class:`CallTimeout` (a
        ``TimeoutError``) if ``timeout`` seconds pass first (the job keeps running).
        """
        if not self.wait(timeout):
            raise CallTimeout("%s (request %d) did not finish within %gs"
                              % (self.op, self.id, timeout))
        if self._error is not None:
            raise self._error
        return dict(self._result or {}), dict(self._arrays)

    def cancel(self) -> bool:
        """Asks the daemon to stop this request; returns False if it had already finished.

        The job then ends with ``TessdError('cancelled')``, even if the daemon completed it
        before the cancel arrived (its result is discarded). Does not wait.
        """
        with self._cond:
            finished = self._done or any(
                item[0] == _FAIL or item[1].get("type") != "progress" for item in self._inbox)
            if finished or self._cancel_sent:
                return False
            self._cancel_sent = True
        try:
            self._client._send_request("cancel", {"id": self.id}, None, None)
        except (OSError, TessdError):
            pass  # the connection is gone: the job fails with that error anyway
        return True

    def __repr__(self) -> str:
        state = "done" if self._done else "running"
        return "<tessd.Job %d %s %s>" % (self.id, self.op, state)


class Client:
    """A connection to a tessd daemon.

    ``socket`` is a path or bare name as for ``tessd serve --socket`` (default: the user's
    default socket). ``timeout`` (seconds; None: no bound) bounds connecting, and is the
    default timeout of each :meth:`call` (and ``ping``, ``hello``, ``hold``, ``release``),
    which bounds the wait for its reply once the request is sent; a call can give its own.
    :meth:`submit` never waits. See the module's documentation. ``use_numpy`` chooses how
    received arrays are returned (default: numpy arrays when numpy is importable, else
    :class:`~tessd.arrays.RawArray`).

    Raises :class:`DaemonUnavailable` when nothing listens on the socket.
    """

    def __init__(self, socket: Optional[str] = None, timeout: Optional[float] = None, *,
                 use_numpy: Optional[bool] = None,
                 max_payload: Optional[int] = DEFAULT_CLIENT_MAX_PAYLOAD):
        from .arrays import has_numpy

        self.socket_path = resolve_socket(socket)
        self.timeout = timeout
        self.use_numpy = has_numpy() if use_numpy is None else bool(use_numpy)
        if self.use_numpy and not has_numpy():
            raise RuntimeError("use_numpy=True but numpy is not importable")
        self._max_payload = max_payload
        self._conn = connect(self.socket_path, timeout)
        self._ids = itertools.count(1)
        self._lock = threading.Lock()  # guards _jobs, _failure, _closed
        self._send_lock = threading.Lock()
        self._jobs: Dict[int, Job] = {}
        self._failure: Optional[BaseException] = None
        self._closed = False
        # The reader holds only a weak reference, so a client nobody closed can still be
        # garbage-collected (its __del__ closes the connection and ends the thread).
        self._reader = threading.Thread(
            target=_reader_main, name="tessd-reader", daemon=True,
            args=(weakref.ref(self), self._conn, self.use_numpy, max_payload, self.socket_path))
        self._reader.start()

    # -- sending ---------------------------------------------------------------------------

    def _send_request(self, op: str, params: Optional[Mapping[str, Any]], arrays: ArraysArg,
                      progress: Optional[ProgressCallback]) -> Job:
        if not isinstance(op, str):
            raise TypeError("op must be a string")
        with self._lock:
            if self._failure is not None:
                raise _fresh(self._failure)
            if self._closed:
                raise DaemonUnavailable("the client is closed")
            job_id = next(self._ids)
            job = Job(self, job_id, op, progress)
            self._jobs[job_id] = job
        message: Dict[str, Any] = {"id": job_id, "op": op}
        if params is not None:
            message["params"] = absolute_paths(op, params)
        try:
            if op not in RAW_ARRAY_OPS:
                try:
                    arrays = prepare_arrays(arrays)
                except ValueError as e:
                    raise _ArrayRefused("invalid_mesh", "%s (not sent)" % e, job_id) from None
            pieces = encode_frame(message, arrays)
        except BaseException:
            with self._lock:
                self._jobs.pop(job_id, None)
            raise
        try:
            with self._send_lock:
                for piece in pieces:
                    self._conn.sendall(piece)
        except BaseException as e:
            # A frame may have gone out in part: the stream is out of step, so the
            # connection is unusable from here on.
            with self._lock:
                self._jobs.pop(job_id, None)
                if self._failure is None:
                    self._failure = DaemonUnavailable(
                        "lost the connection to %s: %s" % (self.socket_path, e))
                failure = self._failure
            self._conn.shutdown()
            if isinstance(e, OSError):
                raise _fresh(failure) from e
            raise
        return job

    def submit(self, op: str, params: Optional[Mapping[str, Any]] = None, arrays: ArraysArg = None,
               progress: Optional[ProgressCallback] = None) -> Job:
        """Sends a request and returns its :class:`Job` at once (non-blocking use).

        ``arrays`` maps names to numpy arrays, ``array.array`` objects, RawArrays or
        ``(dtype, shape, bytes)`` tuples; they are written without being copied. ``progress``
        is called as ``progress(fraction, stage, message)`` from whichever thread polls or
        waits on the job. Paths in ``params`` are made absolute and mesh arrays converted as
        the module's documentation says.
        """
        return self._send_request(op, params, arrays, progress)

    def call(self, op: str, params: Optional[Mapping[str, Any]] = None, arrays: ArraysArg = None,
             progress: Optional[ProgressCallback] = None,
             timeout: Optional[float] = _CLIENT_TIMEOUT) -> Tuple[Dict[str, Any], Dict[str, Any]]:
        """Sends a request and waits for its reply; returns ``(result, arrays)``.

        ``progress(fraction, stage, message)`` is called for each progress frame; returning
        ``False`` cancels the request (a ``cancel`` op is sent) and the call then raises
        :class:`TessdError` with code ``cancelled``. Error replies raise :class:`TessdError`.
        ``timeout`` bounds the wait for the reply, in seconds from when the request was sent
        (default: the client's ``timeout``; ``None``: wait as long as the request runs); when
        it passes, the call cancels the request and raises :class:`CallTimeout` (a
        ``TimeoutError``).
        """
        if timeout is _CLIENT_TIMEOUT:
            timeout = self.timeout
        job = self._send_request(op, params, arrays, progress)
        if not job.wait(timeout):
            job.cancel()
            raise CallTimeout("%s (request %d) did not finish within %gs; cancelled"
                               % (op, job.id, timeout))
        return job.result(0)

    # -- convenience -----------------------------------------------------------------------

    def ping(self, echo: Any = None) -> Any:
        """Round-trips a ``ping``; returns the echoed value."""
        params = {} if echo is None else {"echo": echo}
        result, _ = self.call("ping", params)
        return result.get("echo")

    def hello(self) -> Dict[str, Any]:
        """The daemon's ``hello`` result (server, version, protocol, ops, capabilities, pid,
        holders)."""
        return self.call("hello")[0]

    def hold(self, host: str = "python", pid: Optional[int] = None) -> int:
        """Declares that process ``pid`` (default: this one), a program called ``host``, uses
        the daemon (``session.hold``); returns the number of live holders.

        A host that started a shared daemon stops it on exit only when no holder is left
        (see :func:`tessd.daemon.stop_daemon` with ``only_if_unheld``). A process holds at
        most once; the daemon forgets holders whose process has exited.
        """
        params = {"pid": os.getpid() if pid is None else int(pid), "host": str(host)}
        return int(self.call("session.hold", params)[0]["holders"])

    def release(self, pid: Optional[int] = None) -> int:
        """Withdraws process ``pid``'s hold (default: this process; ``session.release``);
        returns the number of live holders left."""
        params = {"pid": os.getpid() if pid is None else int(pid)}
        return int(self.call("session.release", params)[0]["holders"])

    # -- receiving ---------------------------------------------------------------------------

    def _fail_all(self, failure: BaseException) -> None:
        """Records why the connection ended and fails every job still waiting."""
        with self._lock:
            if self._closed:
                failure = DaemonUnavailable("the client is closed")
            if self._failure is None:
                self._failure = failure
            failure = self._failure
            jobs = list(self._jobs.values())
            self._jobs.clear()
        for job in jobs:
            job._push((_FAIL, failure))

    def _route(self, message: Dict[str, Any], arrays: Dict[str, Any]) -> None:
        job_id = message.get("id")
        final = message.get("type") != "progress"
        if job_id is None:
            # A connection-level error: the daemon closes the connection after it.
            error = _error_from_frame(message)
            with self._lock:
                if self._failure is None:
                    self._failure = error
            return
        with self._lock:
            job = self._jobs.pop(job_id, None) if final else self._jobs.get(job_id)
        if job is not None:
            job._push((_FRAME, message, arrays))

    # -- lifetime ----------------------------------------------------------------------------

    @property
    def in_flight(self) -> int:
        """Number of requests sent whose final reply has not arrived."""
        with self._lock:
            return len(self._jobs)

    def close(self) -> None:
        """Closes the connection; the daemon cancels requests still running on it."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._conn.shutdown()
        if threading.current_thread() is not self._reader:
            self._reader.join()
        self._conn.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        return "<tessd.Client %s>" % self.socket_path


def _reader_main(ref: "weakref.ref[Client]", conn: Any, use_numpy: bool,
                 max_payload: Optional[int], socket_path: str) -> None:
    """The reader thread: reads frames and hands each to the client's router."""
    failure: BaseException
    try:
        while True:
            frame = read_frame(conn.recv_into, use_numpy=use_numpy, max_payload=max_payload)
            if frame is None:
                failure = DaemonUnavailable("the daemon closed the connection")
                break
            client = ref()
            if client is None:
                return
            client._route(*frame)
            del client
    except ProtocolError as e:
        failure = _InvalidReply("invalid frame from %s (is it a tessd daemon?): %s"
                                % (socket_path, e.message), e.code)
    except OSError as e:
        failure = DaemonUnavailable("lost the connection to %s: %s" % (socket_path, e))
    except BaseException as e:  # pragma: no cover - a bug; still fail the jobs
        failure = e
    client = ref()
    if client is not None:
        client._fail_all(failure)


__all__ = ["CallTimeout", "Client", "DaemonUnavailable", "Error", "Job", "PATH_PARAMS", "Progress",
           "TessdError", "absolute_paths"]
