"""The Dask side: one tessd daemon per worker node (or per worker process), and the cluster.

**Daemon per node.** :class:`TessdDaemonPlugin` is a Dask ``WorkerPlugin``: every worker
process, when it starts (and when the nanny restarts it after a crash), runs
:func:`worker_daemon`, which makes sure a ``tessd serve`` answers on the batch's socket
(:func:`tessd.ensure_daemon`) and *holds* it (``session.hold`` with the worker's pid). With the
default scope ``"node"`` the socket is keyed by the cluster and the host name only
(``<socket dir>/batch-<cluster key>-<host>.sock``), so all worker processes of one node share
one daemon: the first to start spawns it (detached, in its own session), the others find it
answering. The daemon serves each connection on its own threads and runs
its parallel passes on all cores, so one daemon per node uses the node's cores without N
copies of its memory. Starts and stops are serialised on the node by an flock (``batch-start.lock``
in the socket folder, :func:`_start_lock`). With scope ``"worker"`` the socket also carries the worker's name (each
process gets its own daemon; a nanny-restarted worker keeps its name and so finds its daemon
again).

The daemon outlives a worker killed with SIGKILL (it is in its own session); its hold dies with
the process (the daemon prunes holders whose pid is gone), and the restarted worker holds it
again. On a clean shutdown each worker's ``teardown`` releases its hold and asks the daemon to
stop *only if unheld* (``shutdown`` with ``if_unheld``): the last worker of the node stops it.

Tasks find the daemon through the same :func:`worker_daemon` (a worker-local lazy singleton:
the plugin only starts it early), so they also work on a worker that came up before the plugin
was registered. ``tessd`` is found as :func:`tessd.daemon.find_binary` finds it (``binary``,
else ``$TESSD_BIN`` of the worker, else ``PATH``).
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import re
import socket as _socket
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, Optional, Tuple

import tessd
from tessd.daemon import ensure_daemon, stop_daemon
from tessd.transport import DaemonUnavailable

SCOPES = ("node", "worker")


@dataclass(frozen=True)
class DaemonConfig:
    """Where and how the workers' daemons run (picklable: it travels with every task)."""

    key: str  # the cluster's key: sockets of two clusters on one node never clash
    scope: str = "node"
    binary: Optional[str] = None
    socket_dir: Optional[str] = None
    args: Tuple[str, ...] = field(default_factory=tuple)  # extra `tessd serve` arguments
    start_timeout: float = 30.0


def cluster_key(scheduler_address: str) -> str:
    """A short key for a cluster (its scheduler's address)."""
    return hashlib.sha1(scheduler_address.encode()).hexdigest()[:10]


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9]", "", _socket.gethostname())[:20] or "host"


def socket_for(cfg: DaemonConfig, worker_name: Any = None) -> str:
    """The daemon socket of this node (scope ``node``) or of worker ``worker_name`` on it."""
    name = "batch-%s-%s" % (cfg.key, _host())
    if cfg.scope == "worker":
        name += "-w" + (re.sub(r"[^A-Za-z0-9]", "", str(worker_name))[:16] or "0")
    elif cfg.scope != "node":
        raise ValueError("daemon scope must be one of %s, not %r" % (SCOPES, cfg.scope))
    if cfg.socket_dir:
        return os.path.join(cfg.socket_dir, name + ".sock")
    return tessd.resolve_socket(name, create_dir=True)


# ---------------------------------------------------------------------------------------------
# The worker-local daemon

_lock = threading.Lock()
_sockets: Dict[DaemonConfig, str] = {}  # the daemons this process holds, by config


def _current_worker_name() -> Any:
    try:
        from distributed import get_worker

        return get_worker().name
    except (ImportError, ValueError):
        return os.getpid()


def worker_daemon(cfg: DaemonConfig, restart: bool = False, worker_name: Any = None) -> str:
    """The socket of this worker's daemon, started (and held) when it does not answer.

    ``restart``: the caller lost its connection: check it again (and start a new one when the
    old one died). A daemon that goes away between the start and the hold (another worker's
    teardown stopped it: holds are counted at that moment) is started again, up to 3 times."""
    with _lock:
        path = _sockets.get(cfg)
        if path is not None and not restart:
            return path
        if worker_name is None:
            worker_name = _current_worker_name()
        path = socket_for(cfg, worker_name)
        for attempt in range(3):
            with _start_lock(os.path.dirname(path)):
                ensure_daemon(path, binary=cfg.binary, timeout=cfg.start_timeout, args=cfg.args)
            try:
                with tessd.Client(path, timeout=10.0) as c:
                    c.hold(host="tessd.batch")
                break
            except DaemonUnavailable:
                if attempt == 2:
                    raise
                time.sleep(0.2)
        _sockets[cfg] = path
        return path


@contextlib.contextmanager
def _start_lock(folder: str) -> Iterator[None]:
    """Serialises daemon starts and stops on this node (an flock on
    ``<socket dir>/batch-start.lock``).

    The daemon itself is safe against simultaneous starts (core/ipc/src/socket.rs ``bind``
    takes its own lock around the stale-socket check, so exactly one binds). This lock is about
    the workers: the second worker's ensure_daemon finds the first one's daemon answering
    instead of spawning a process that would only exit "already serving", and a last worker's
    stop-if-unheld does not run while another worker is starting or joining the daemon."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: no flock (and no Unix socket files)
        yield
        return
    fd = os.open(os.path.join(folder, "batch-start.lock"), os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def release_worker_daemon(cfg: DaemonConfig, stop: bool = True) -> bool:
    """Releases this process's hold on ``cfg``'s daemon and (``stop``) stops it when nobody
    else holds it; returns whether it stopped."""
    with _lock:
        path = _sockets.pop(cfg, None)
    if path is None:
        return False
    try:
        with tessd.Client(path, timeout=10.0) as c:
            c.release()
    except Exception:
        return False
    if not stop:
        return False
    try:
        with _start_lock(os.path.dirname(path)):  # not while another worker starts / joins it
            stopped = stop_daemon(path, timeout=10.0, only_if_unheld=True)
    except Exception:
        return False
    if stopped:  # a clean stop: its log (ensure_daemon's, beside the socket) is not needed
        try:
            os.unlink(path[: -len(".sock")] + ".log" if path.endswith(".sock") else path + ".log")
        except OSError:
            pass
    return stopped


def daemon_info() -> Dict[str, Any]:
    """This worker's daemon(s): socket, pid, holders (for checks: ``client.run(daemon_info)``);
    the first one's fields at the top level."""
    found = []
    for cfg, path in list(_sockets.items()):
        with tessd.Client(path, timeout=10.0) as c:
            hello = c.hello()
        found.append({"socket": path, "scope": cfg.scope, "pid": hello.get("pid"),
                      "holders": hello.get("holders")})
    info: Dict[str, Any] = dict(found[0]) if found else {"socket": None}
    info.update(worker_pid=os.getpid(), daemons=found)
    return info


def _plugin_base() -> type:
    from distributed import WorkerPlugin

    return WorkerPlugin


class TessdDaemonPlugin(_plugin_base()):  # type: ignore[misc]
    """Starts (or joins) the node's tessd daemon on every worker; stops it with the last one.

    Register it with ``client.register_plugin(TessdDaemonPlugin(cfg))``; Dask runs ``setup``
    on every worker, present and future (restarted ones included). Its name is derived from
    the config and it is idempotent: registering it again (the next batch on the same cluster)
    changes nothing, rather than tearing every worker's hold down and up again at once."""

    idempotent = True

    def __init__(self, cfg: DaemonConfig):
        self.cfg = cfg
        self.name = "tessd-daemon-" + hashlib.sha1(repr(cfg).encode()).hexdigest()[:12]

    def setup(self, worker: Any) -> None:
        worker_daemon(self.cfg, restart=True, worker_name=worker.name)

    def teardown(self, worker: Any) -> None:
        release_worker_daemon(self.cfg, stop=True)


# ---------------------------------------------------------------------------------------------
# Clusters


def local_cluster(workers: int = 2, allowed_failures: int = 3, **kwargs: Any) -> Any:
    """A ``LocalCluster`` of ``workers`` worker processes with one thread each (the daemon does
    the parallel work), its HTTP server (dashboard, health) on a free loopback port, and
    ``allowed_failures`` (how many worker deaths a task may survive before it is reported
    lost)."""
    import dask
    from distributed import LocalCluster

    opts = dict(n_workers=workers, threads_per_worker=1, processes=True,
                dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
    opts.update(kwargs)
    with dask.config.set({"distributed.scheduler.allowed-failures": allowed_failures}):
        return LocalCluster(**opts)


def worker_losses(client: Any, keys: Any) -> Dict[str, int]:
    """Per task key, how many workers died while running it (the scheduler's ``suspicious``
    count; the task was resubmitted that many times). Keys the scheduler forgot are left out."""
    def _suspicious(dask_scheduler: Any = None, keys: Any = ()) -> Dict[str, int]:
        out = {}
        for k in keys:
            ts = dask_scheduler.tasks.get(k)
            if ts is not None:
                out[k] = int(getattr(ts, "suspicious", 0))
        return out

    return client.run_on_scheduler(_suspicious, keys=list(keys))


__all__ = ["DaemonConfig", "SCOPES", "TessdDaemonPlugin", "cluster_key", "daemon_info",
           "local_cluster", "release_worker_daemon", "socket_for", "worker_daemon", "worker_losses"]
