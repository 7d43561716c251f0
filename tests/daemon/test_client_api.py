"""The Python client's rough edges of issue 32, point 7, against a real daemon on a real socket:

- relative paths in `params` name files in the caller's working folder, not the daemon's;
- numpy's default integer arrays (int64), int32, uint64, uint16 and array.array / tuple ones are
  sent as the u32 the daemon reads, and values that do not fit are refused naming the array;
- `except tessd.Error` catches every failure kind the client raises;
- `Client(timeout=...)` and a call's own `timeout` (None: no bound).
"""

from __future__ import annotations

import array
import os
import shutil
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import tessd
from daemon_util import RawConn
from tessd.client import PATH_PARAMS
from tessd.frame import encode_frame_bytes

#: The daemon's ops that name no file (everything else must be in tessd.client.PATH_PARAMS).
NO_PATH_OPS = {"hello", "ping", "cancel", "shutdown", "session.hold", "session.release",
               "debug.echo", "debug.sleep"}

TETRA_POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TETRA_FACES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


@pytest.fixture
def client(daemon):
    with tessd.Client(daemon.socket, timeout=60) as c:
        yield c


@pytest.fixture
def elsewhere(tmp_path, monkeypatch, shared_data):
    """A working folder that is not the daemon's, holding `in/suzanne.obj`."""
    assert Path.cwd().resolve() != tmp_path.resolve()
    (tmp_path / "in").mkdir()
    shutil.copy(shared_data / "mesh" / "suzanne.obj", tmp_path / "in" / "suzanne.obj")
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ------------------------------------------------------------------------------------------
# Paths


def test_relative_input_reads_the_callers_file(daemon, client, elsewhere):
    absolute, _ = client.call("mesh.stats", {"input": str(elsewhere / "in" / "suzanne.obj")})
    params = {"input": "in/suzanne.obj"}
    relative, _ = client.call("mesh.stats", params)
    print("\nrelative from %s: %d vertices, %d faces" % (elsewhere, relative["vertices"],
                                                           relative["faces"]))
    assert relative == absolute and relative["faces"] == 500
    assert params == {"input": "in/suzanne.obj"}, "the caller's params were changed"
    # What the client no longer sends: the bare relative path resolves in the daemon's folder.
    with RawConn(daemon.socket) as raw:
        reply = raw.request({"id": 1, "op": "mesh.stats", "params": {"input": "in/suzanne.obj"}})
    print("sent as is:", reply["error"])
    assert reply["error"]["code"] == "io" and "in/suzanne.obj" in reply["error"]["message"]


def test_relative_outputs_and_other_path_params(client, elsewhere):
    result, _ = client.call("mesh.convert", {"input": Path("in/suzanne.obj"),
                                             "output": "out.ply"})
    assert result["output"] == str(elsewhere / "out.ply")
    assert (elsewhere / "out.ply").is_file()
    cmp_, _ = client.call("compare", {"a": "in/suzanne.obj", "b": "out.ply"})
    assert cmp_["hausdorff"] < 1e-5
    (elsewhere / "levels").mkdir()
    lod, _ = client.call("lod", {"input": "in/suzanne.obj", "levels": "50%",
                                 "output": "chain.usda", "per_level": "levels"})
    assert (elsewhere / "chain.usda").is_file()
    assert sorted(p.name for p in (elsewhere / "levels").iterdir()), lod
    simp, _ = client.call("simplify", {"input": "in/suzanne.obj", "method": "grid", "cells": 8,
                                       "output": "s.obj", "partition_output": "cells.obj"})
    assert (elsewhere / "s.obj").is_file() and (elsewhere / "cells.obj").is_file(), simp
    # Values that are no path are left alone: `per_level: true` writes beside `output`.
    client.call("lod", {"input": "in/suzanne.obj", "levels": "50%", "output": "beside.usda",
                        "per_level": True, "name": "in/not_a_path"})
    assert any(p.name.startswith("beside") and p.suffix == ".obj" for p in elsewhere.iterdir())


def test_every_file_op_of_the_daemon_has_its_paths_listed(client):
    ops = set(client.hello()["ops"])
    assert set(PATH_PARAMS) <= ops, set(PATH_PARAMS) - ops
    assert ops - set(PATH_PARAMS) - NO_PATH_OPS == set(), (
        "ops naming files unknown to tessd.client.PATH_PARAMS")


def test_render_input_list_is_resolved_item_by_item(elsewhere):
    params = tessd.client.absolute_paths("render", {"input": ["in/a.obj", "/abs/b.obj"],
                                                    "output": "o.png", "view": "front"})
    assert params == {"input": [str(elsewhere / "in" / "a.obj"), "/abs/b.obj"],
                      "output": str(elsewhere / "o.png"), "view": "front"}


# ------------------------------------------------------------------------------------------
# Integer arrays


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.uint64, np.uint16, np.int16])
def test_integer_face_arrays_are_sent_as_u32(client, dtype):
    faces = np.array(TETRA_FACES, dtype=dtype)
    result, _ = client.call("mesh.stats", {}, {"positions": TETRA_POSITIONS, "face_indices": faces})
    assert (result["faces"], result["vertices"], result["boundary_edges"]) == (4, 4, 0)
    flat = faces.reshape(-1).astype(np.int64)
    result, _ = client.call("mesh.stats", {}, {"positions": TETRA_POSITIONS, "face_indices": flat,
                                               "face_sizes": np.full(4, 3, dtype=np.int32)})
    assert result["faces"] == 4


def test_numpy_default_int64_is_what_the_daemon_refuses_alone(daemon):
    """The client's conversion is what makes int64 work: the same frame sent raw is refused."""
    faces = np.array(TETRA_FACES)
    assert faces.dtype == np.int64
    frame = encode_frame_bytes({"id": 3, "op": "mesh.stats"},
                               {"positions": TETRA_POSITIONS, "face_indices": faces})
    with RawConn(daemon.socket) as raw:
        raw.send(frame)
        reply = raw.final(3)
    print("\nraw int64:", reply["error"]["message"])
    assert reply["error"]["code"] == "invalid_mesh" and "i64" in reply["error"]["message"]


def test_array_array_and_tuples_without_numpy(client):
    faces = array.array("q", [i for f in TETRA_FACES for i in f])
    sizes = ("u64", (4,), np.full(4, 3, dtype="<u8").tobytes())
    result, _ = client.call("mesh.stats", {}, {"positions": TETRA_POSITIONS, "face_indices": faces,
                                               "face_sizes": sizes})
    assert result["faces"] == 4


def test_float_arrays_go_as_given(client):
    """Only integer arrays are converted: f64 normals get the daemon's own dtype error."""
    normals = np.tile(np.array([0.0, 0.0, 1.0]), (12, 1))
    with pytest.raises(tessd.TessdError, match=r'"normals" has dtype f64; expected f32'):
        client.call("mesh.convert", {}, {"positions": TETRA_POSITIONS,
                                         "face_indices": np.array(TETRA_FACES), "normals": normals})


@pytest.mark.parametrize("bad, value, why", [
    (np.array([[0, 2, 1], [0, 1, -1]]), "-1", "negative"),
    (np.array([[0, 2, 1], [0, 1, 2 ** 32]], dtype=np.uint64), "4294967296", "above 4294967295"),
    (np.array([[0, 2, 1], [0, 1, 2 ** 40]], dtype=np.int64), "1099511627776", "above 4294967295"),
])
def test_values_that_do_not_fit_are_refused_naming_the_array(client, bad, value, why):
    with pytest.raises(tessd.Error) as info:
        client.call("mesh.stats", {}, {"positions": TETRA_POSITIONS, "face_indices": bad})
    e = info.value
    print("\nrefused:", e)
    assert isinstance(e, tessd.TessdError) and isinstance(e, ValueError)
    assert e.code == "invalid_mesh"
    assert "'face_indices'" in e.message and value in e.message and why in e.message
    assert "flat index 5" in e.message
    assert client.in_flight == 0 and client.ping("still usable") == "still usable"


def test_too_large_array_array_is_refused(client):
    with pytest.raises(tessd.TessdError, match=r"'face_groups'.*-3 at flat index 1.*negative"):
        client.call("mesh.stats", {}, {"positions": TETRA_POSITIONS,
                                       "face_indices": np.array(TETRA_FACES),
                                       "face_groups": array.array("i", [0, -3, 0, 0])})


def test_debug_echo_sends_arrays_as_given(client):
    _, arrays = client.call("debug.echo", {}, {"face_indices": np.array([1, 2], dtype=np.int64)})
    assert arrays["face_indices"].dtype == np.int64


# ------------------------------------------------------------------------------------------
# One base class for every failure


def test_error_is_the_base_of_every_kind():
    for kind in (tessd.TessdError, tessd.DaemonUnavailable, tessd.DaemonStartError,
                 tessd.ProtocolError, tessd.CallTimeout):
        assert issubclass(kind, tessd.Error), kind
    # and they keep their other bases
    assert issubclass(tessd.DaemonUnavailable, ConnectionError)
    assert issubclass(tessd.DaemonStartError, tessd.DaemonUnavailable)
    assert issubclass(tessd.CallTimeout, TimeoutError)


def test_except_error_catches_an_error_reply(client):
    try:
        client.call("mesh.stats", {"input": "/nonexistent/tessd/x.obj"})
    except tessd.Error as e:
        caught = e
    assert type(caught) is tessd.TessdError and caught.code == "io"


def test_except_error_catches_a_missing_daemon(tmpdir_short):
    try:
        tessd.Client(os.path.join(tmpdir_short, "nobody.sock"), timeout=2)
    except tessd.Error as e:
        caught = e
    assert isinstance(caught, tessd.DaemonUnavailable), caught
    assert "no tessd daemon is listening" in str(caught)


def test_except_error_catches_a_bad_binary(tmpdir_short, tmp_path):
    try:
        tessd.ensure_daemon(os.path.join(tmpdir_short, "d.sock"),
                            binary=str(tmp_path / "nope" / "tessd"), timeout=5)
    except tessd.Error as e:
        caught = e
    assert isinstance(caught, tessd.DaemonStartError), caught
    assert "nope/tessd" in str(caught)


def test_except_error_catches_garbage_from_the_socket(tmpdir_short):
    """Another program on the socket (here an HTTP-ish server): a ProtocolError."""
    path = os.path.join(tmpdir_short, "http.sock")
    server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    server.bind(path)
    server.listen(1)

    def serve():
        conn, _ = server.accept()
        with conn:
            conn.recv(65536)
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 2)
            time.sleep(0.5)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        with tessd.Client(path, timeout=10) as c:
            try:
                c.call("ping")
            except tessd.Error as e:
                caught = e
    finally:
        thread.join(5)
        server.close()
    print("\ngarbage:", caught)
    assert isinstance(caught, tessd.ProtocolError), type(caught).__mro__
    assert isinstance(caught, tessd.TessdError) and caught.code == "invalid_frame"
    assert "bad magic" in str(caught) and path in str(caught)


# ------------------------------------------------------------------------------------------
# Timeouts


def test_a_calls_own_timeout_fires_and_cancels(client):
    t0 = time.monotonic()
    with pytest.raises(tessd.Error) as info:
        client.call("debug.sleep", {"seconds": 20, "steps": 200}, timeout=0.5)
    waited = time.monotonic() - t0
    print("\ntimed out after %.2fs: %s" % (waited, info.value))
    assert isinstance(info.value, tessd.CallTimeout) and isinstance(info.value, TimeoutError)
    assert 0.5 <= waited < 5
    # the request was cancelled: the connection is free again at once
    assert client.ping(1) == 1
    deadline = time.monotonic() + 5
    while client.in_flight and time.monotonic() < deadline:
        time.sleep(0.02)
    assert client.in_flight == 0


def test_the_clients_timeout_is_the_default_and_none_waits(daemon):
    with tessd.Client(daemon.socket, timeout=0.3) as c:
        with pytest.raises(tessd.CallTimeout):
            c.call("debug.sleep", {"seconds": 3, "steps": 30})
        t0 = time.monotonic()
        result, _ = c.call("debug.sleep", {"seconds": 0.8, "steps": 8}, timeout=None)
        assert result["steps"] == 8 and time.monotonic() - t0 >= 0.8
        result, _ = c.call("debug.sleep", {"seconds": 0.6, "steps": 6}, timeout=5)
        assert result["steps"] == 6


# ------------------------------------------------------------------------------------------
# Errors that point to the next step


_BLOCK = """
import runpy, sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("OCP", "dask", "distributed"):
            raise ModuleNotFoundError("No module named %r" % name, name=name)
sys.meta_path.insert(0, Block())
sys.argv = sys.argv[1:]
runpy.run_module(sys.argv[0], run_name="__main__", alter_sys=True)
"""


@pytest.mark.parametrize("argv, extra, venv", [
    (["tessd.brep", "export", "part.step", "part.json"], "cad", ".venv-cad"),
    (["tessd.batch", "meshes", "library"], "batch", ".venv-cad"),
])
def test_a_missing_module_names_its_extra_and_venv(tmp_path, argv, extra, venv):
    """OCP and dask are hidden from a real interpreter; the commands say where they come from."""
    import subprocess
    import sys
    import tomllib

    repo = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=str(repo / "python"))
    proc = subprocess.run([sys.executable, "-c", _BLOCK, *argv], cwd=tmp_path, env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=60)
    print("\n" + proc.stderr.strip())
    assert proc.returncode in (1, 2) and "Traceback" not in proc.stderr, proc.stderr
    assert sys.executable in proc.stderr and venv in proc.stderr
    assert "pip install './python[%s]'" % extra in proc.stderr
    with open(repo / "python" / "pyproject.toml", "rb") as f:
        extras = tomllib.load(f)["project"]["optional-dependencies"]
    assert extra in extras, extras
