"""tessd: the Python client of the tessd geometry daemon.

Pure standard library (numpy is used when importable: received arrays are numpy arrays then,
else :class:`~tessd.arrays.RawArray` objects). See docs/protocol.md for the wire protocol.

    import tessd
    path = tessd.ensure_daemon()
    with tessd.Client(path) as c:
        stats, _ = c.call("mesh.stats", {"input": "/data/bunny.ply"})

Every exception the client raises on purpose is a :class:`tessd.Error`: :class:`TessdError`
(an error reply), :class:`DaemonUnavailable`, :class:`DaemonStartError`, :class:`ProtocolError`
and :class:`CallTimeout` (see :mod:`tessd.errors`).
"""

from .arrays import RawArray
from .client import Client, Job, Progress, TessdError
from .errors import CallTimeout, Error
from .daemon import DaemonStartError, ensure_daemon, stop_daemon
from .frame import ProtocolError
from .mesh_arrays import MeshArrays, arrays_to_mesh, mesh_to_arrays
from .socket_path import default_socket_path, resolve_socket
from .transport import DaemonUnavailable

__version__ = "0.1.0"

__all__ = [
    "CallTimeout",
    "Client",
    "DaemonStartError",
    "DaemonUnavailable",
    "Error",
    "Job",
    "MeshArrays",
    "Progress",
    "ProtocolError",
    "RawArray",
    "TessdError",
    "__version__",
    "arrays_to_mesh",
    "default_socket_path",
    "ensure_daemon",
    "mesh_to_arrays",
    "resolve_socket",
    "stop_daemon",
]
