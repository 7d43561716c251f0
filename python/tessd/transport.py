"""Byte-stream connections to the daemon: a Unix-domain socket, or a Windows named pipe.

Both offer the same three methods the client needs: ``sendall(buffer)``,
``recv_into(view) -> int`` (0 at EOF) and ``close()``, and are safe to read from one thread
while another writes.
"""

from __future__ import annotations

import socket
import time
from typing import Any, Optional

from .errors import Error
from .socket_path import is_windows


class DaemonUnavailable(ConnectionError, Error):
    """No tessd daemon is listening on the socket (or the connection to it was lost).

    A ``ConnectionError`` (so an ``OSError``) as before, and a :class:`tessd.Error`."""


class UnixTransport:
    """A connected ``AF_UNIX`` stream socket."""

    def __init__(self, path: str, timeout: Optional[float] = None):
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            sock.settimeout(timeout)
            sock.connect(path)
        except (FileNotFoundError, ConnectionRefusedError, NotADirectoryError) as e:
            sock.close()
            raise DaemonUnavailable("no tessd daemon is listening on %s (%s)"
                                    % (path, e.strerror or e)) from None
        except socket.timeout:
            sock.close()
            raise DaemonUnavailable("timed out connecting to %s" % path) from None
        except OSError:
            sock.close()
            raise
        sock.settimeout(None)
        self._sock = sock
        self.path = path

    def sendall(self, data: Any) -> None:
        """Writes all of ``data``."""
        self._sock.sendall(data)

    def recv_into(self, view: memoryview) -> int:
        """Reads into ``view``; returns the byte count, 0 at EOF."""
        return self._sock.recv_into(view)

    def shutdown(self) -> None:
        """Wakes a thread blocked in :meth:`recv_into` (it then sees EOF)."""
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass

    def close(self) -> None:
        """Closes the socket."""
        self._sock.close()


class PipeTransport:  # pragma: no cover - Windows only, untested here
    """A Windows named-pipe client handle opened for overlapped I/O.

    Overlapped I/O lets the reader thread wait in ``ReadFile`` while another thread writes;
    with a synchronous handle Windows would serialize the two.
    """

    _ERROR_FILE_NOT_FOUND = 2
    _ERROR_BROKEN_PIPE = 109
    _ERROR_PIPE_BUSY = 231
    _ERROR_IO_PENDING = 997
    _CHUNK = 1 << 20

    def __init__(self, path: str, timeout: Optional[float] = None):
        import _winapi

        self._w = _winapi
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            try:
                self._handle = _winapi.CreateFile(
                    path, _winapi.GENERIC_READ | _winapi.GENERIC_WRITE, 0, _winapi.NULL,
                    _winapi.OPEN_EXISTING, _winapi.FILE_FLAG_OVERLAPPED, _winapi.NULL)
                break
            except OSError as e:
                if e.winerror == self._ERROR_FILE_NOT_FOUND:
                    raise DaemonUnavailable("no tessd daemon is listening on %s" % path) from None
                if e.winerror != self._ERROR_PIPE_BUSY:
                    raise
                if deadline is not None and time.monotonic() >= deadline:
                    raise DaemonUnavailable("timed out connecting to %s" % path) from None
                try:  # every instance busy: wait up to 100 ms for one, then try again
                    _winapi.WaitNamedPipe(path, 100)
                except OSError:  # ERROR_SEM_TIMEOUT, or the pipe went away: CreateFile says
                    pass
        self.path = path
        self._closed = False
        self._pending_read = None

    def sendall(self, data: Any) -> None:
        view = memoryview(data).cast("B")
        while len(view):
            chunk = view[: self._CHUNK]
            ov, err = self._w.WriteFile(self._handle, chunk, overlapped=True)
            written, err = ov.GetOverlappedResult(True)
            if err:
                raise BrokenPipeError("write to %s failed (error %d)" % (self.path, err))
            view = view[written:]

    def recv_into(self, view: memoryview) -> int:
        try:
            ov, err = self._w.ReadFile(self._handle, min(len(view), self._CHUNK), overlapped=True)
            self._pending_read = ov
            n, err = ov.GetOverlappedResult(True)
        except OSError as e:
            if e.winerror == self._ERROR_BROKEN_PIPE or self._closed:
                return 0
            raise
        finally:
            self._pending_read = None
        if err == self._ERROR_BROKEN_PIPE or self._closed:
            return 0
        view[:n] = ov.getbuffer()[:n]
        return n

    def shutdown(self) -> None:
        self._closed = True
        ov = self._pending_read
        if ov is not None:
            try:
                ov.cancel()
            except OSError:
                pass

    def close(self) -> None:
        self._closed = True
        self._w.CloseHandle(self._handle)


def connect(path: str, timeout: Optional[float] = None) -> Any:
    """Opens a connection to the daemon at ``path`` (a socket path, or a pipe on Windows)."""
    if is_windows():  # pragma: no cover
        return PipeTransport(path, timeout)
    return UnixTransport(path, timeout)
