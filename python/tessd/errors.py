"""The client's exception hierarchy: one base, :class:`Error`, for everything it raises.

    try:
        with tessd.Client() as c:
            c.call("mesh.stats", {"input": "bunny.ply"})
    except tessd.Error as e:      # any of the kinds below
        print("tessd:", e)

- :class:`~tessd.TessdError`: an error reply from the daemon (``code``, ``message``), or the
  client's equivalent (``cancelled``; ``invalid_mesh`` for an array refused before sending).
- :class:`~tessd.DaemonUnavailable` (also a ``ConnectionError``): nothing listens on the
  socket, or the connection was lost.
- :class:`~tessd.DaemonStartError` (a ``DaemonUnavailable``): ``ensure_daemon`` could not
  find, run or start the daemon.
- :class:`~tessd.ProtocolError`: bytes that are not a valid frame (e.g. something other than
  tessd listens on the socket).
- :class:`CallTimeout` (also a ``TimeoutError``): a call's timeout passed.

This module imports nothing else of the package, so every module can use it.
"""

from __future__ import annotations


class Error(Exception):
    """Base class of every exception the tessd client raises on purpose."""


class CallTimeout(Error, TimeoutError):
    """A call (or :meth:`~tessd.Job.result`) did not finish within its timeout.

    Also a ``TimeoutError``, which is what earlier versions raised. :meth:`~tessd.Client.call`
    has sent a ``cancel`` for the request before raising.
    """


__all__ = ["CallTimeout", "Error"]
