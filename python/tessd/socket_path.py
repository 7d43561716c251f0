"""Where the daemon listens (docs/protocol.md, "Transport").

- Linux/macOS: ``$XDG_RUNTIME_DIR/tessd.sock`` when ``XDG_RUNTIME_DIR`` is set and is a
  directory, else ``<tmp>/tessd-<uid>/tessd.sock`` with ``<tmp>`` = ``$TMPDIR`` or ``/tmp``
  (that directory is created with mode 0700).
- Windows: the named pipe ``\\\\.\\pipe\\tessd-<username>``.

A socket argument containing a path separator is a path used as is; a bare name ``N`` means
``<default directory>/N.sock`` (on Windows, the pipe ``\\\\.\\pipe\\N``).
"""

from __future__ import annotations

import getpass
import os
import stat
import sys
from typing import Optional, Union

PathLike = Union[str, "os.PathLike[str]"]

#: File name of the default socket inside the default directory.
DEFAULT_NAME = "tessd"

PIPE_PREFIX = "\\\\.\\pipe\\"


def is_windows() -> bool:
    """Whether sockets are Windows named pipes here."""
    return sys.platform == "win32"


def _username() -> str:
    try:
        return getpass.getuser()
    except Exception:  # pragma: no cover - no user database entry
        return "user"


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
        return PIPE_PREFIX + "tessd-" + _username()
    return os.path.join(default_socket_dir(create=create_dir), DEFAULT_NAME + ".sock")


def _has_separator(value: str) -> bool:
    if "/" in value:
        return True
    return is_windows() and "\\" in value


def resolve_socket(name_or_path: Optional[PathLike] = None, create_dir: bool = False) -> str:
    """The socket path for a ``--socket`` value, as the daemon resolves it.

    ``None`` or ``""`` gives :func:`default_socket_path`; a value with a path separator is used
    as is; a bare name ``N`` gives ``<default dir>/N.sock`` (``\\\\.\\pipe\\N`` on Windows).
    """
    if name_or_path is None:
        return default_socket_path(create_dir)
    value = os.fspath(name_or_path)
    if not value:
        return default_socket_path(create_dir)
    if _has_separator(value):
        return value
    if is_windows():
        return PIPE_PREFIX + value
    return os.path.join(default_socket_dir(create=create_dir), value + ".sock")


__all__ = ["default_socket_dir", "default_socket_path", "resolve_socket", "is_windows"]
