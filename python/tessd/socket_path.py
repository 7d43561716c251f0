"""Where the daemon listens (docs/protocol.md, "Transport").

- Linux/macOS: ``$XDG_RUNTIME_DIR/tessd.sock`` when ``XDG_RUNTIME_DIR`` is set and is a
  directory, else ``<tmp>/tessd-<uid>/tessd.sock`` with ``<tmp>`` = ``$TMPDIR`` or ``/tmp``
  (that directory is created with mode 0700).
- Windows: the named pipe ``\\\\.\\pipe\\tessd-<user>``, ``<user>`` being ``%USERNAME%`` with
  every character outside ``[A-Za-z0-9._-]`` replaced by ``_`` (:func:`pipe_user`).

On Linux and macOS a socket argument containing a path separator is a path used as is, and a
bare name ``N`` means ``<default directory>/N.sock``. On Windows (:func:`windows_pipe`) a bare
name ``N`` means the pipe ``\\\\.\\pipe\\tessd-<user>-N``, a value starting with
``\\\\.\\pipe\\`` is a pipe name used as is, and any other path-like value (a drive letter, a UNC
name, a separator) is refused with :class:`SocketNameError`: the daemon listens on named pipes
only there. The daemon resolves ``--socket`` by the same rules (core/ipc/src/socket.rs).
"""

from __future__ import annotations

import os
import re
import stat
import sys
from typing import Optional, Union

from .errors import Error

PathLike = Union[str, "os.PathLike[str]"]

#: File name of the default socket inside the default directory.
DEFAULT_NAME = "tessd"

#: The prefix of every Windows named pipe name (``\\.\pipe\``).
PIPE_PREFIX = "\\\\.\\pipe\\"


class SocketNameError(ValueError, Error):
    """A socket value that cannot name the daemon's endpoint on this platform: on Windows, a
    file path (a drive letter, a UNC name, a separator), where the daemon serves named pipes
    only. Also a ``ValueError``; the message names the value and says what is accepted."""


def is_windows() -> bool:
    """Whether sockets are Windows named pipes here."""
    return sys.platform == "win32"


_NOT_PIPE_USER = re.compile(r"[^A-Za-z0-9._-]")


def pipe_user(username: Optional[str]) -> str:
    """``<user>`` in the Windows pipe names: ``username`` (the value of ``%USERNAME%``) with
    every character outside ``[A-Za-z0-9._-]`` replaced by ``_`` (one per character);
    ``user`` when it is unset or empty."""
    if not username:
        return "user"
    return _NOT_PIPE_USER.sub("_", username)


def windows_pipe(value: Optional[str], username: Optional[str]) -> str:
    r"""The named pipe a ``--socket`` value names on Windows, for the user ``username``
    (``%USERNAME%``, see :func:`pipe_user`). A pure function of its arguments, whatever the
    platform it runs on:

    - ``None`` or ``""``: ``\\.\pipe\tessd-<user>``;
    - a value starting with ``\\.\pipe\`` (the prefix in any case, a name after it): that
      pipe, as it is;
    - a bare name ``N`` (no ``\``, ``/`` or ``:``): ``\\.\pipe\tessd-<user>-N``;
    - anything else (a drive letter, a UNC name, a relative path): :class:`SocketNameError`.
    """
    base = PIPE_PREFIX + "tessd-" + pipe_user(username)
    if not value:
        return base
    if value[: len(PIPE_PREFIX)].lower() == PIPE_PREFIX and len(value) > len(PIPE_PREFIX):
        return value  # Windows' names are case-insensitive: \\.\PIPE\x is the same pipe
    if any(c in value for c in "\\/:"):
        raise SocketNameError(
            "socket '%s' is not accepted on Windows, where the tessd daemon listens on a named "
            "pipe, never on a file: give a bare name N (the pipe %s-N), a full pipe name "
            "starting with %s, or nothing (the pipe %s)" % (value, base, PIPE_PREFIX, base))
    return base + "-" + value


def default_socket_dir(create: bool = False) -> Optional[str]:
    """The per-user directory holding sockets (``None`` on Windows, which uses named pipes).

    With ``create``, a missing ``<tmp>/tessd-<uid>`` directory is created with mode 0700;
    ``$XDG_RUNTIME_DIR`` is never created (it must already exist to be used).
    """
    if is_windows():
        return None
    xdg = os.environ.get("XDG_RUNTIME_DIR")
    if xdg and os.path.isdir(xdg):
        return xdg
    tmp = os.environ.get("TMPDIR") or "/tmp"
    directory = os.path.join(tmp, "tessd-%d" % os.getuid())
    if create:
        _make_private_dir(directory)
    return directory


def _make_private_dir(directory: str) -> None:
    """Creates ``directory`` with mode 0700; refuses one that belongs to another user."""
    try:
        os.mkdir(directory, 0o700)
    except FileExistsError:
        pass
    st = os.lstat(directory)
    if not stat.S_ISDIR(st.st_mode):
        raise NotADirectoryError("%s exists and is not a directory" % directory)
    if st.st_uid != os.getuid():
        raise PermissionError("%s belongs to another user (uid %d)" % (directory, st.st_uid))
    if stat.S_IMODE(st.st_mode) != 0o700:
        os.chmod(directory, 0o700)


def default_socket_path(create_dir: bool = False) -> str:
    """The default socket of this user: a filesystem path, or a named pipe on Windows.

    With ``create_dir``, the ``<tmp>/tessd-<uid>`` directory is created (mode 0700) if that is
    where the socket lives.
    """
    if is_windows():
        return windows_pipe(None, os.environ.get("USERNAME"))
    return os.path.join(default_socket_dir(create=create_dir), DEFAULT_NAME + ".sock")


def resolve_socket(name_or_path: Optional[PathLike] = None, create_dir: bool = False) -> str:
    r"""The socket path for a ``--socket`` value, as the daemon resolves it.

    ``None`` or ``""`` gives :func:`default_socket_path`. On Linux and macOS a value with a
    ``/`` is used as is and a bare name ``N`` gives ``<default dir>/N.sock``; on Windows the
    rules of :func:`windows_pipe` apply (a bare name gives ``\\.\pipe\tessd-<user>-N``, a file
    path raises :class:`SocketNameError`).
    """
    value = "" if name_or_path is None else os.fspath(name_or_path)
    if is_windows():
        return windows_pipe(value, os.environ.get("USERNAME"))
    if not value:
        return default_socket_path(create_dir)
    if "/" in value:
        return value
    return os.path.join(default_socket_dir(create=create_dir), value + ".sock")


__all__ = ["PIPE_PREFIX", "SocketNameError", "default_socket_dir", "default_socket_path",
           "is_windows", "pipe_user", "resolve_socket", "windows_pipe"]
