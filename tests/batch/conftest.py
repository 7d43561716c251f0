"""Fixtures of the tessd.batch tests: one real Dask LocalCluster (2 worker processes, one thread
each) for the module, the real daemon binary, and usd-core run in a subprocess (the CAD venv
these tests run in has no ``pxr``; the tests' .venv has usd-core 26.11).

Run: ``.venv-cad/bin/python -m pytest tests/batch`` (needs dask[distributed], OCP and the
release binary: TESSD_BIN, else target/release/tessd)."""

from __future__ import annotations

import os
import pytest

import locate

@pytest.fixture(scope="session", autouse=True)
def tessd_bin_env():
    """Workers (spawned processes) find the daemon through TESSD_BIN: set it for them."""
    os.environ.setdefault("TESSD_BIN", str(locate.tessd_bin()))
    assert os.access(os.environ["TESSD_BIN"], os.X_OK), os.environ["TESSD_BIN"]
    return os.environ["TESSD_BIN"]


@pytest.fixture(scope="module")
def dask_client(tessd_bin_env):
    """A real LocalCluster of 2 worker processes (1 thread each) and its client; at the end,
    checks that the workers' teardown stopped their daemon."""
    from distributed import Client

    from tessd.batch import cluster as batch_cluster

    cl = batch_cluster.local_cluster(2, allowed_failures=3)
    client = Client(cl)
    client.wait_for_workers(2, timeout=60)
    key = batch_cluster.cluster_key(client.scheduler.address)
    try:
        yield client
    finally:
        client.close()
        cl.close()
    sock = batch_cluster.socket_for(batch_cluster.DaemonConfig(key=key))
    import tessd.daemon

    assert not tessd.daemon.ping(sock, timeout=1.0), \
        "the node's daemon still runs after the cluster closed: " + sock
