"""Malformed frames and bad requests, sent on raw sockets to a real daemon.

Framing errors (the byte stream is out of step) must get exactly one error frame with
`"id": null` and then the connection closes. Errors inside a well-framed request get an error
frame carrying the request's id and the connection stays usable (checked with a ping on the
same connection). At the end the daemon must still be alive and serving.
"""

from __future__ import annotations

import json
import os
import random
import struct
import time

import numpy as np
import pytest

import tessd
from daemon_util import RawConn, array_entry, raw_frame
from tessd import TessdError

MiB = 1 << 20
PING = {"id": 1, "op": "ping"}


# ------------------------------------------------------------------------------------------
# Helpers


def rss_kib(pid: int) -> int:
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def expect_framing_error(daemon, data: bytes, code: str, *, shut_write: bool = False) -> dict:
    """Sends `data` on a fresh connection; expects one error frame with id null, then EOF."""
    with RawConn(daemon.socket) as conn:
        conn.send(data)
        if shut_write:
            conn.shut_write()
        frame = conn.recv_frame()
        assert frame is not None, "the daemon closed the connection without an error frame"
        message = frame[0]
        assert message.get("type") == "error", message
        assert message.get("id", "missing") is None, message
        assert message["error"]["code"] == code, message
        assert isinstance(message["error"].get("message"), str) and message["error"]["message"]
        assert conn.at_eof(), "the connection stayed open after a framing error"
    return message


def expect_request_error(conn: RawConn, body, code: str, payload: bytes = b"", *,
                         reply_id="same") -> dict:
    """Sends a well-framed bad request; expects an error with its id; then checks the same
    connection still answers a ping."""
    conn.send(raw_frame(body, payload))
    message = conn.final()
    assert message.get("type") == "error", message
    assert message["error"]["code"] == code, message
    if reply_id == "same":
        reply_id = body.get("id")
    assert message.get("id", "missing") == reply_id, message
    echo = "still-alive-%d" % random.randrange(1 << 30)
    ok = conn.request({"id": 987654, "op": "ping", "params": {"echo": echo}})
    assert ok["type"] == "ok" and ok["result"] == {"pong": True, "echo": echo}, ok
    return message


@pytest.fixture
def conn(daemon):
    with RawConn(daemon.socket) as c:
        yield c


@pytest.fixture
def client(daemon):
    with tessd.Client(daemon.socket, timeout=30) as c:
        yield c


def payload_of(*arrays):
    """A hand-built array table and payload from (name, dtype, shape, bytes) items."""
    table, payload = [], b""
    for name, dtype, shape, data in arrays:
        payload += b"\0" * (-len(payload) % 8)
        table.append(array_entry(name, dtype, list(shape), len(payload), len(data)))
        payload += data
    return table, payload


# ------------------------------------------------------------------------------------------
# Framing errors: one error frame with id null, then the connection closes.

ENTRY = array_entry("a", "f32", [2], 0, 8)

FRAMING = {
    "wrong_magic": (raw_frame(PING, magic=b"TSDD"), "invalid_frame"),
    "http_request": (b"GET / HTTP/1.1\r\nHost: x\r\n\r\n", "invalid_frame"),
    "wrong_version_0": (raw_frame(PING, version=0), "invalid_frame"),
    "wrong_version_2": (raw_frame(PING, version=2), "invalid_frame"),
    "nonzero_flags": (raw_frame(PING, flags=1), "invalid_frame"),
    "nonzero_reserved": (raw_frame(PING, reserved=0xDEAD), "invalid_frame"),
    "json_len_0": (raw_frame(b"", json_len=0), "invalid_frame"),
    "json_len_over_16MiB": (raw_frame(b"", json_len=16 * MiB + 1), "too_large"),
    "json_len_max_u32": (raw_frame(b"", json_len=0xFFFFFFFF), "too_large"),
    "invalid_utf8": (raw_frame(b'{"id":1,"op":"pi\xffng"}'), "invalid_frame"),
    "not_json": (raw_frame(b"{id: 1, op: ping}"), "invalid_frame"),
    "json_with_trailing_garbage": (raw_frame(b'{"id":1,"op":"ping"} x'), "invalid_frame"),
    "json_array": (raw_frame([{"id": 1, "op": "ping"}]), "invalid_frame"),
    "json_number": (raw_frame(7), "invalid_frame"),
    "json_string": (raw_frame('"ping"'), "invalid_frame"),
    "json_null": (raw_frame(None), "invalid_frame"),
    "arrays_not_a_list": (raw_frame(dict(PING, arrays={"a": ENTRY}), b"\0" * 8), "invalid_frame"),
    "array_entry_not_object": (raw_frame(dict(PING, arrays=["a"]), b"\0" * 8), "invalid_frame"),
    "array_entry_missing_dtype": (raw_frame(dict(PING, arrays=[{k: v for k, v in ENTRY.items() if k != "dtype"}]), b"\0" * 8), "invalid_frame"),
    "array_entry_missing_shape": (raw_frame(dict(PING, arrays=[{k: v for k, v in ENTRY.items() if k != "shape"}]), b"\0" * 8), "invalid_frame"),
    "array_entry_missing_offset": (raw_frame(dict(PING, arrays=[{k: v for k, v in ENTRY.items() if k != "offset"}]), b"\0" * 8), "invalid_frame"),
    "unknown_dtype": (raw_frame(dict(PING, arrays=[dict(ENTRY, dtype="f16", length=4)]), b"\0" * 8), "invalid_frame"),
    "shape_times_itemsize_not_length": (raw_frame(dict(PING, arrays=[dict(ENTRY, length=12)]), b"\0" * 16), "invalid_frame"),
    "negative_shape": (raw_frame(dict(PING, arrays=[dict(ENTRY, shape=[-2])]), b"\0" * 8), "invalid_frame"),
    "offset_not_multiple_of_8": (raw_frame(dict(PING, arrays=[dict(ENTRY, offset=4)]), b"\0" * 16), "invalid_frame"),
    "offset_plus_length_over_payload": (raw_frame(dict(PING, arrays=[dict(ENTRY, offset=8)]), b"\0" * 8), "invalid_frame"),
    "huge_offset_overflow": (raw_frame(dict(PING, arrays=[dict(ENTRY, offset=2 ** 64 - 8)]), b"\0" * 8), "invalid_frame"),
    "huge_shape_overflow": (raw_frame(dict(PING, arrays=[dict(ENTRY, shape=[2 ** 62, 8], length=8)]), b"\0" * 8), "invalid_frame"),
    "duplicate_array_names": (raw_frame(dict(PING, arrays=[ENTRY, dict(ENTRY, offset=8)]), b"\0" * 16), "invalid_frame"),
    "overlapping_arrays": (raw_frame(dict(PING, arrays=[dict(ENTRY, shape=[4], length=16), dict(ENTRY, name="b", offset=8)]), b"\0" * 16), "invalid_frame"),
}


@pytest.mark.parametrize("case", list(FRAMING))
def test_framing_error(daemon, case):
    data, code = FRAMING[case]
    expect_framing_error(daemon, data, code)


def test_payload_len_2_pow_62_is_refused_without_allocating(daemon):
    before = rss_kib(daemon.pid)
    start = time.monotonic()
    # Header and JSON only: the daemon must answer without waiting for (or allocating) 4 EiB.
    message = expect_framing_error(daemon, raw_frame(PING, payload_len=2 ** 62), "too_large")
    assert time.monotonic() - start < 5
    assert rss_kib(daemon.pid) - before < 64 * 1024, "daemon memory grew"
    assert str(2 ** 62) in message["error"]["message"]


def test_payload_len_just_over_default_limit(daemon):
    expect_framing_error(daemon, raw_frame(PING, payload_len=4 * 1024 ** 3 + 1), "too_large")


@pytest.mark.parametrize("cut", ["header", "json", "payload"])
@pytest.mark.parametrize("how", ["half_close", "close"])
def test_truncated_frame(daemon, cut, how):
    table, payload = payload_of(("a", "f32", [4], b"\0" * 16))
    full = raw_frame(dict(PING, arrays=table), payload)
    json_end = len(full) - len(payload)
    data = {"header": full[:10], "json": full[:json_end - 5], "payload": full[:-3]}[cut]
    if how == "half_close":
        # The daemon sees EOF mid-frame but can still answer.
        expect_framing_error(daemon, data, "invalid_frame", shut_write=True)
    else:
        with RawConn(daemon.socket) as c:
            c.send(data)
    # Either way the daemon keeps serving.
    with tessd.Client(daemon.socket, timeout=10) as c:
        assert c.ping("after-truncation") == "after-truncation"


# ------------------------------------------------------------------------------------------
# Well-framed bad requests: error with the request's id; the connection stays usable.

ENVELOPE = {
    "missing_op": ({"id": 5}, "invalid_request", "same"),
    "op_not_a_string": ({"id": 6, "op": 42}, "invalid_request", "same"),
    "op_null": ({"id": 7, "op": None}, "invalid_request", "same"),
    "unknown_op": ({"id": 8, "op": "mesh.explode"}, "invalid_request", "same"),
    "empty_op": ({"id": 9, "op": ""}, "invalid_request", "same"),
    "id_missing": ({"op": "ping"}, "invalid_request", None),
    "id_negative": ({"id": -1, "op": "ping"}, "invalid_request", "same"),
    "id_string": ({"id": "7", "op": "ping"}, "invalid_request", "same"),
    "id_float": ({"id": 1.5, "op": "ping"}, "invalid_request", "same"),
    "params_not_an_object": ({"id": 10, "op": "ping", "params": [1, 2]}, "invalid_request", "same"),
    "params_string": ({"id": 11, "op": "mesh.stats", "params": "bunny.obj"}, "invalid_request", "same"),
    "mesh_stats_without_input": ({"id": 12, "op": "mesh.stats"}, "invalid_request", "same"),
    "mesh_stats_input_not_a_string": ({"id": 13, "op": "mesh.stats", "params": {"input": 3}}, "invalid_request", "same"),
    "cancel_without_target": ({"id": 14, "op": "cancel", "params": {}}, "invalid_request", "same"),
    "debug_sleep_bad_steps": ({"id": 15, "op": "debug.sleep", "params": {"seconds": 0.01, "steps": 0}}, "invalid_request", "same"),
}


@pytest.mark.parametrize("case", list(ENVELOPE))
def test_bad_request(conn, case):
    body, code, reply_id = ENVELOPE[case]
    message = expect_request_error(conn, body, code, reply_id=reply_id)
    if case == "unknown_op":
        assert "mesh.explode" in message["error"]["message"]


@pytest.mark.parametrize("second_op", ["debug.sleep", "ping"])
def test_duplicate_in_flight_id(conn, second_op):
    conn.send(raw_frame({"id": 77, "op": "debug.sleep", "params": {"seconds": 0.5, "steps": 5}}))
    conn.send(raw_frame({"id": 77, "op": second_op, "params": {"seconds": 0.1, "steps": 1}}))
    finals = []
    while len(finals) < 2:
        frame = conn.recv_frame()
        assert frame is not None
        if frame[0]["type"] != "progress":
            finals.append(frame[0])
    errors = [m for m in finals if m["type"] == "error"]
    oks = [m for m in finals if m["type"] == "ok"]
    assert len(errors) == 1 and errors[0]["error"]["code"] == "invalid_request", finals
    assert "77" in errors[0]["error"]["message"]
    assert len(oks) == 1 and oks[0]["result"]["steps"] == 5, finals
    assert conn.request({"id": 78, "op": "ping", "params": {"echo": 1}})["result"]["echo"] == 1


def test_cancel_of_unknown_id(conn):
    reply = conn.request({"id": 3, "op": "cancel", "params": {"id": 123456}})
    assert reply["type"] == "ok" and reply["result"] == {"cancelled": False}, reply
    assert conn.request({"id": 4, "op": "ping"})["type"] == "ok"


# ------------------------------------------------------------------------------------------
# Bad meshes (valid frames): invalid_mesh / io / unsupported with messages naming the culprit.

QUAD_POS = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0)


def mesh_request(conn, arrays, op="mesh.stats", request_id=21, params=None):
    table, payload = payload_of(*arrays)
    body = {"id": request_id, "op": op, "params": params or {}, "arrays": table}
    return body, payload


def u32(*values):
    return struct.pack("<%dI" % len(values), *values)


MESH_CASES = {
    "face_index_out_of_range": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [2, 3], u32(0, 1, 2, 0, 2, 9))],
        ["face 1", "uses vertex 9"]),
    "nan_position": (
        [("positions", "f32", [4, 3], QUAD_POS[:24] + struct.pack("<3f", 1, float("nan"), 0) + QUAD_POS[36:]),
         ("face_indices", "u32", [2, 3], u32(0, 1, 2, 0, 2, 3))],
        ["vertex 2"]),
    "inf_position_f64": (
        [("positions", "f64", [3, 3], struct.pack("<9d", 0, 0, 0, 1, 0, 0, 0, 1, float("inf"))),
         ("face_indices", "u32", [1, 3], u32(0, 1, 2))],
        ["vertex 2"]),
    "face_with_2_vertices": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [5], u32(0, 1, 2, 2, 3)),
         ("face_sizes", "u32", [2], u32(3, 2))],
        ["face 1", "2 vertices"]),
    "faces_of_2_columns": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [2, 2], u32(0, 1, 2, 3))],
        []),
    "face_sizes_sum_not_indices": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [6], u32(0, 1, 2, 0, 2, 3)),
         ("face_sizes", "u32", [2], u32(3, 4))],
        ["face_sizes"]),
    "face_sizes_sum_short": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [6], u32(0, 1, 2, 0, 2, 3)),
         ("face_sizes", "u32", [1], u32(3))],
        ["face_sizes"]),
    "positions_shape_n_by_2": (
        [("positions", "f32", [6, 2], QUAD_POS), ("face_indices", "u32", [1, 3], u32(0, 1, 2))],
        ["positions"]),
    "positions_wrong_dtype": (
        [("positions", "u32", [4, 3], QUAD_POS), ("face_indices", "u32", [1, 3], u32(0, 1, 2))],
        ["positions"]),
    "face_indices_wrong_dtype": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "i64", [1, 3], struct.pack("<3q", 0, 1, 2))],
        ["face_indices"]),
    "face_indices_1d_without_sizes": (
        [("positions", "f32", [4, 3], QUAD_POS), ("face_indices", "u32", [3], u32(0, 1, 2))],
        ["face_sizes"]),
    "missing_face_indices": ([("positions", "f32", [4, 3], QUAD_POS)], ["face_indices"]),
}


@pytest.mark.parametrize("case", list(MESH_CASES))
def test_bad_mesh_arrays(conn, case):
    arrays, needles = MESH_CASES[case]
    body, payload = mesh_request(conn, arrays)
    message = expect_request_error(conn, body, "invalid_mesh", payload)
    for needle in needles:
        assert needle in message["error"]["message"], message


def test_input_that_does_not_exist(client, tmp_path):
    missing = tmp_path / "no" / "such.obj"
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(missing)})
    assert info.value.code == "io", info.value
    assert "such.obj" in info.value.message
    assert client.ping(1) == 1


def test_input_that_is_a_folder(client, tmp_path):
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(tmp_path) + "/"})
    assert info.value.code in ("io", "unsupported"), info.value
    assert client.ping(2) == 2


def test_truncated_ascii_ply(client, shared_data, tmp_path):
    data = (shared_data / "mesh" / "bun_zipper.ply").read_bytes()
    bad = tmp_path / "truncated.ply"
    bad.write_bytes(data[: len(data) // 2])
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(bad)})
    assert info.value.code == "invalid_mesh", info.value
    assert client.ping(3) == 3


def test_truncated_binary_ply(client, tmp_path):
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 2\n"
              b"property list uchar int vertex_indices\nend_header\n")
    body = QUAD_POS + b"\x03" + struct.pack("<3i", 0, 1, 2) + b"\x03" + struct.pack("<2i", 0, 2)
    bad = tmp_path / "truncated_bin.ply"
    bad.write_bytes(header + body)  # the last face lacks its third index
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(bad)})
    assert info.value.code == "invalid_mesh", info.value
    assert client.ping(4) == 4


def test_obj_ending_mid_line_with_bad_token(client, tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 1.0 2.0 3.x")
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(bad)})
    assert info.value.code == "invalid_mesh", info.value
    assert "3.x" in info.value.message and ":5" in info.value.message, info.value.message
    assert client.ping(5) == 5


def test_obj_face_index_out_of_range(client, tmp_path):
    bad = tmp_path / "range.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
    with pytest.raises(TessdError) as info:
        client.call("mesh.stats", {"input": str(bad)})
    assert info.value.code == "invalid_mesh", info.value
    assert client.ping(6) == 6


def test_convert_to_unsupported_extension_leaves_no_file(client, shared_data, tmp_path):
    out = tmp_path / "out.xyz"
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(TessdError) as info:
        client.call("mesh.convert", {"input": str(shared_data / "mesh" / "spot_triangulated.obj"),
                                     "output": str(out)})
    assert info.value.code == "unsupported", info.value
    assert not out.exists()
    assert sorted(os.listdir(tmp_path)) == before, "a partial or temporary file was left behind"
    assert client.ping(7) == 7


def test_convert_into_a_missing_folder(client, shared_data, tmp_path):
    out = tmp_path / "missing" / "out.ply"
    with pytest.raises(TessdError) as info:
        client.call("mesh.convert", {"input": str(shared_data / "mesh" / "spot_triangulated.obj"),
                                     "output": str(out)})
    assert info.value.code == "io", info.value
    assert not out.exists()


# ------------------------------------------------------------------------------------------
# Random garbage


def garbage_blobs(n: int, seed: int = 1234):
    """Random blobs: pure noise, a valid magic and version followed by noise, and a valid
    header followed by random JSON bytes."""
    rng = random.Random(seed)
    for i in range(n):
        kind = i % 3
        if kind == 0:
            blob = bytes(rng.getrandbits(8) for _ in range(rng.randrange(1, 200)))
            if blob[:4] == b"TSSD":  # astronomically unlikely; keep the expectation simple
                blob = b"X" + blob[1:]
        elif kind == 1:
            blob = b"TSSD\x01\x00" + bytes(rng.getrandbits(8) for _ in range(rng.randrange(0, 200)))
        else:
            json_len = rng.randrange(8, 200)
            blob = struct.pack("<4sHHIIQ", b"TSSD", 1, 0, json_len, 0, rng.randrange(0, 4096))
            blob += bytes(rng.getrandbits(8) for _ in range(json_len))
        yield blob


def test_1000_garbage_blobs(daemon):
    codes = {}
    for i, blob in enumerate(garbage_blobs(1000)):
        with RawConn(daemon.socket) as c:
            c.send(blob)
            c.shut_write()
            frame = c.recv_frame()
            assert frame is not None, "blob %d: closed without an error frame: %r" % (i, blob[:40])
            message = frame[0]
            assert message["type"] == "error" and message["id"] is None, (i, message)
            code = message["error"]["code"]
            assert code in ("invalid_frame", "too_large"), (i, message)
            codes[code] = codes.get(code, 0) + 1
            assert c.at_eof()
    assert codes.get("invalid_frame", 0) > 500, codes


# ------------------------------------------------------------------------------------------
# Last: after all of the above, the daemon is alive and a fresh client is served correctly.


def test_zz_daemon_still_serves(daemon):
    assert daemon.alive(), daemon.log_tail()
    with tessd.Client(daemon.socket, timeout=10) as c:
        assert c.ping({"after": "everything"}) == {"after": "everything"}
        hello = c.hello()
        assert hello["server"] == "tessd" and hello["protocol"] == 1
        assert hello["pid"] == daemon.pid
        for op in ("hello", "ping", "mesh.stats", "mesh.convert", "shutdown", "cancel"):
            assert op in hello["ops"], hello
    assert daemon.alive()
