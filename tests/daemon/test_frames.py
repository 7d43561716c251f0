"""Unit tests of the Python frame codec (no daemon needed)."""

from __future__ import annotations

import array
import json
import os
import stat
import struct

import numpy as np
import pytest

from daemon_util import HEADER, raw_frame
from tessd import RawArray, arrays_to_mesh, mesh_to_arrays
from tessd.arrays import DTYPES, ITEMSIZE, to_wire
from tessd.frame import (
    HEADER_SIZE,
    MAX_JSON_LEN,
    ProtocolError,
    decode_frame,
    encode_frame,
    encode_frame_bytes,
    pack_header,
    read_frame,
    unpack_header,
)
from tessd.socket_path import default_socket_dir, default_socket_path, resolve_socket

NP = {"u8": np.uint8, "u16": np.uint16, "u32": np.uint32, "u64": np.uint64,
      "i32": np.int32, "i64": np.int64, "f32": np.float32, "f64": np.float64}


def sample(dtype: str, shape=(7, 3)) -> np.ndarray:
    t = NP[dtype]
    if dtype.startswith("f"):
        info = np.finfo(t)
        values = [0.0, -0.0, 1.5, -2.25, info.max, info.min, info.tiny, np.inf, -np.inf]
    else:
        info = np.iinfo(t)
        values = [0, 1, info.max, info.min, info.max // 3, 42]
    n = int(np.prod(shape))
    return np.array((values * (n // len(values) + 1))[:n], dtype=t).reshape(shape)


def frame_of(message, payload=b"", **header) -> bytes:
    return raw_frame(message, payload, **header)


# ------------------------------------------------------------------------------------------
# Round trips


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("shape", [(), (0,), (1,), (5,), (7, 3), (0, 3), (2, 3, 4)])
def test_round_trip_every_dtype_and_shape(dtype, shape):
    arr = sample(dtype, shape)
    data = encode_frame_bytes({"id": 1, "op": "x"}, {"a": arr, "pad": np.zeros(1, np.uint8)})
    message, arrays = decode_frame(data)
    assert message["arrays"][0]["dtype"] == dtype
    assert message["arrays"][0]["shape"] == list(shape)
    out = arrays["a"]
    assert out.dtype == arr.dtype and out.shape == arr.shape
    assert out.tobytes() == arr.tobytes()
    # Without numpy: RawArray with the same bytes and the same nested lists.
    _, raw = decode_frame(data, use_numpy=False)
    assert isinstance(raw["a"], RawArray)
    assert raw["a"].dtype == dtype and raw["a"].shape == shape
    assert raw["a"].data.tobytes() == arr.tobytes()
    expected = arr.tolist()
    got = raw["a"].tolist()
    if dtype.startswith("f"):
        assert np.array_equal(np.array(got, dtype=arr.dtype).reshape(shape), arr)
    else:
        assert got == expected


def test_alignment_and_zero_padding():
    arrays = {"a": np.arange(3, dtype=np.uint8), "b": np.arange(5, dtype=np.uint16),
              "c": np.arange(1, dtype=np.float64), "d": np.arange(3, dtype=np.float32),
              "e": np.zeros(0, dtype=np.uint32), "f": np.arange(2, dtype=np.int64)}
    data = encode_frame_bytes({"id": 1, "op": "x"}, arrays)
    magic, version, flags, json_len, reserved, payload_len = HEADER.unpack_from(data)
    assert (magic, version, flags, reserved) == (b"TSSD", 1, 0, 0)
    assert len(data) == HEADER_SIZE + json_len + payload_len
    table = json.loads(data[HEADER_SIZE:HEADER_SIZE + json_len])["arrays"]
    payload = data[HEADER_SIZE + json_len:]
    covered = bytearray(len(payload))
    for entry in table:
        assert entry["offset"] % 8 == 0
        assert entry["length"] == int(np.prod(entry["shape"])) * ITEMSIZE[entry["dtype"]]
        for i in range(entry["offset"], entry["offset"] + entry["length"]):
            covered[i] = 1
        assert payload[entry["offset"]:entry["offset"] + entry["length"]] == arrays[entry["name"]].tobytes()
    # Every byte not in an array is zero padding.
    assert all(b == 0 for b, c in zip(payload, covered) if not c)
    assert [e["offset"] for e in table] == [0, 8, 24, 32, 48, 48]


def test_every_input_kind_is_accepted():
    arrays = {
        "np": np.arange(6, dtype=np.float32).reshape(2, 3),
        "np_strided": np.arange(20, dtype=np.int32)[::2],  # not contiguous: copied
        "np_bigendian": np.arange(4, dtype=">u4"),
        "aa": array.array("d", [1.0, 2.5]),
        "aa_u": array.array("I", [1, 2, 3]),
        "tuple": ("u16", [2, 2], struct.pack("<4H", 1, 2, 3, 4)),
        "tuple_mv": ("i64", 1, memoryview(struct.pack("<q", -5))),
        "raw": RawArray("u8", (3,), b"xyz"),
    }
    _, out = decode_frame(encode_frame_bytes({"id": 1, "op": "x"}, arrays))
    assert out["np"].tolist() == [[0, 1, 2], [3, 4, 5]]
    assert out["np_strided"].tolist() == list(range(0, 20, 2))
    assert out["np_bigendian"].tolist() == [0, 1, 2, 3] and out["np_bigendian"].dtype == np.dtype("<u4")
    assert out["aa"].tolist() == [1.0, 2.5] and out["aa"].dtype == np.float64
    assert out["aa_u"].tolist() == [1, 2, 3] and out["aa_u"].dtype == np.uint32
    assert out["tuple"].tolist() == [[1, 2], [3, 4]]
    assert out["tuple_mv"].tolist() == [-5]
    assert out["raw"].tobytes() == b"xyz"


def test_arrays_are_sent_without_copying():
    big = np.arange(1000, dtype=np.float64)
    pieces = encode_frame({"id": 1, "op": "x"}, {"big": big})
    assert len(pieces) == 2
    assert np.shares_memory(np.frombuffer(pieces[1], dtype=np.uint8), big)


def test_received_arrays_view_one_buffer():
    data = bytearray(encode_frame_bytes({"id": 1, "op": "x"},
                                        {"a": np.arange(4, dtype=np.uint32), "b": np.ones(2)}))
    _, out = decode_frame(data)
    data[-1] = 0x7F  # last byte of b's last element: the decoded view sees it
    assert out["b"][1] != 1.0


@pytest.mark.parametrize("bad, error", [
    (np.zeros(3, dtype=np.bool_), TypeError),
    (np.zeros(3, dtype=np.int8), TypeError),
    (np.zeros(3, dtype=np.float16), TypeError),
    (np.zeros(3, dtype=np.complex64), TypeError),
    (array.array("b", [1]), TypeError),
    (("f17", [1], b"1234"), TypeError),
    (("f32", [2], b"1234"), ValueError),
    (("u8", [-1], b""), ValueError),
    ([1, 2, 3], TypeError),
])
def test_encoder_rejects_unsendable_arrays(bad, error):
    with pytest.raises(error):
        encode_frame({"id": 1, "op": "x"}, {"a": bad})


def test_encoder_rejects_nan_params_and_duplicate_names():
    with pytest.raises(ValueError):
        encode_frame({"id": 1, "op": "x", "params": {"v": float("nan")}})
    with pytest.raises(ValueError):
        encode_frame({"id": 1, "op": "x"}, [("a", np.zeros(1)), ("a", np.zeros(1))])


# ------------------------------------------------------------------------------------------
# Rejections


GOOD = {"id": 1, "op": "ping"}


def entry(name="a", dtype="f32", shape=(2,), offset=0, length=8):
    return {"name": name, "dtype": dtype, "shape": list(shape), "offset": offset, "length": length}


BAD_FRAMES = {
    "bad_magic": (frame_of(GOOD, magic=b"TSSX"), "invalid_frame"),
    "lowercase_magic": (frame_of(GOOD, magic=b"tssd"), "invalid_frame"),
    "version_0": (frame_of(GOOD, version=0), "invalid_frame"),
    "version_2": (frame_of(GOOD, version=2), "invalid_frame"),
    "flags": (frame_of(GOOD, flags=1), "invalid_frame"),
    "flags_high": (frame_of(GOOD, flags=0x8000), "invalid_frame"),
    "reserved": (frame_of(GOOD, reserved=1), "invalid_frame"),
    "short_header": (frame_of(GOOD)[:23], "invalid_frame"),
    "empty": (b"", "invalid_frame"),
    "json_len_0": (frame_of(b"", json_len=0), "invalid_frame"),
    "json_too_long": (frame_of(GOOD, json_len=MAX_JSON_LEN + 1), "too_large"),
    "payload_too_long": (frame_of(GOOD, payload_len=2 ** 62), "too_large"),
    "truncated_json": (frame_of(GOOD)[:-3], "invalid_frame"),
    "truncated_payload": (frame_of(dict(GOOD, arrays=[entry()]), b"\0" * 8)[:-1], "invalid_frame"),
    "trailing_bytes": (frame_of(GOOD) + b"\0", "invalid_frame"),
    "invalid_utf8": (frame_of(b'{"op":"\xff\xfe"}'), "invalid_frame"),
    "not_json": (frame_of(b"{op: ping}"), "invalid_frame"),
    "json_nan": (frame_of(b'{"id":1,"v":NaN}'), "invalid_frame"),
    "json_array": (frame_of([1, 2]), "invalid_frame"),
    "json_number": (frame_of(3), "invalid_frame"),
    "json_string": (frame_of('"ping"'), "invalid_frame"),
    "json_null": (frame_of(None), "invalid_frame"),
    "arrays_not_list": (frame_of(dict(GOOD, arrays={"a": 1})), "invalid_frame"),
    "array_entry_not_object": (frame_of(dict(GOOD, arrays=[1])), "invalid_frame"),
    "array_missing_name": (frame_of(dict(GOOD, arrays=[{k: v for k, v in entry().items() if k != "name"}]), b"\0" * 8), "invalid_frame"),
    "array_missing_length": (frame_of(dict(GOOD, arrays=[{k: v for k, v in entry().items() if k != "length"}]), b"\0" * 8), "invalid_frame"),
    "array_name_not_string": (frame_of(dict(GOOD, arrays=[dict(entry(), name=5)]), b"\0" * 8), "invalid_frame"),
    "unknown_dtype": (frame_of(dict(GOOD, arrays=[entry(dtype="f16", length=4)]), b"\0" * 8), "invalid_frame"),
    "negative_shape": (frame_of(dict(GOOD, arrays=[entry(shape=(-2,))]), b"\0" * 8), "invalid_frame"),
    "float_shape": (frame_of(dict(GOOD, arrays=[entry(shape=(2.0,))]), b"\0" * 8), "invalid_frame"),
    "bool_offset": (frame_of(dict(GOOD, arrays=[entry(offset=False)]), b"\0" * 8), "invalid_frame"),
    "length_mismatch": (frame_of(dict(GOOD, arrays=[entry(length=12)]), b"\0" * 16), "invalid_frame"),
    "misaligned_offset": (frame_of(dict(GOOD, arrays=[entry(offset=4)]), b"\0" * 16), "invalid_frame"),
    "out_of_payload": (frame_of(dict(GOOD, arrays=[entry(offset=8)]), b"\0" * 8), "invalid_frame"),
    "overlapping": (frame_of(dict(GOOD, arrays=[entry("a", shape=(4,), length=16), entry("b", offset=8)]), b"\0" * 16), "invalid_frame"),
    "duplicate_names": (frame_of(dict(GOOD, arrays=[entry("a"), entry("a", offset=8)]), b"\0" * 16), "invalid_frame"),
}


@pytest.mark.parametrize("name", sorted(BAD_FRAMES))
def test_decoder_rejects(name):
    data, code = BAD_FRAMES[name]
    with pytest.raises(ProtocolError) as info:
        decode_frame(data)
    assert info.value.code == code, str(info.value)


def test_header_limits_are_checked_before_allocation():
    header = pack_header(10, 2 ** 63)
    with pytest.raises(ProtocolError) as info:
        unpack_header(header)
    assert info.value.code == "too_large"
    assert unpack_header(header, max_payload=None).payload_len == 2 ** 63


def test_empty_arrays_at_the_end_of_the_payload_are_valid():
    data = frame_of(dict(GOOD, arrays=[entry("a"), entry("e", shape=(0, 3), offset=8, length=0)]), b"\0" * 8)
    _, arrays = decode_frame(data)
    assert arrays["e"].shape == (0, 3)


# ------------------------------------------------------------------------------------------
# Streaming reads


class Chunks:
    """A recv_into over fixed bytes that returns at most `step` bytes per call."""

    def __init__(self, data: bytes, step: int):
        self.data, self.pos, self.step = data, 0, step

    def __call__(self, view: memoryview) -> int:
        n = min(len(view), self.step, len(self.data) - self.pos)
        view[:n] = self.data[self.pos:self.pos + n]
        self.pos += n
        return n


@pytest.mark.parametrize("step", [1, 7, 1 << 20])
def test_read_frame_from_a_stream(step):
    a = np.arange(30, dtype=np.float32).reshape(10, 3)
    stream = encode_frame_bytes({"id": 1, "type": "ok"}, {"a": a}) + encode_frame_bytes({"id": 2, "type": "ok"})
    recv = Chunks(stream, step)
    m1, arr1 = read_frame(recv)
    m2, arr2 = read_frame(recv)
    assert (m1["id"], m2["id"]) == (1, 2)
    assert np.array_equal(arr1["a"], a) and arr2 == {}
    assert read_frame(recv) is None  # EOF at a frame boundary


@pytest.mark.parametrize("cut", [5, HEADER_SIZE, HEADER_SIZE + 3, -1])
def test_read_frame_eof_inside_a_frame(cut):
    data = encode_frame_bytes({"id": 1, "type": "ok"}, {"a": np.zeros(3)})
    with pytest.raises(ProtocolError):
        read_frame(Chunks(data[:cut], 4))


def test_read_frame_validates_the_table_before_reading_the_payload():
    # A table pointing outside the payload is rejected without reading the payload.
    data = frame_of(dict(GOOD, arrays=[entry(offset=64)]), b"")
    head = data  # no payload bytes at all
    with pytest.raises(ProtocolError) as info:
        read_frame(Chunks(head, 1 << 20))
    assert "outside the payload" in str(info.value)


# ------------------------------------------------------------------------------------------
# RawArray and mesh arrays


def test_raw_array_helpers():
    raw = RawArray("i32", (2, 2), struct.pack("<4i", 1, -2, 3, -4))
    assert raw.tolist() == [[1, -2], [3, -4]]
    assert raw.to_array().tolist() == [1, -2, 3, -4]
    assert list(raw.flat()) == [1, -2, 3, -4]
    assert len(raw) == 2 and raw.size == 4 and raw.nbytes == 16 and raw.ndim == 2
    assert RawArray("f64", (), struct.pack("<d", 2.5)).tolist() == 2.5
    assert RawArray("u8", (0, 3), b"").tolist() == []
    with pytest.raises(ValueError):
        RawArray("u32", (3,), b"12")
    assert to_wire(raw).shape == (2, 2)


def test_mesh_arrays_forms():
    positions = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]]
    ragged = mesh_to_arrays(positions, [[0, 1, 2, 3], [1, 4, 2]])
    assert ragged["positions"].dtype == np.float64 and ragged["positions"].shape == (5, 3)
    assert ragged["face_indices"].dtype == np.uint32 and ragged["face_indices"].tolist() == [0, 1, 2, 3, 1, 4, 2]
    assert ragged["face_sizes"].tolist() == [4, 3]
    quads = mesh_to_arrays(np.array(positions, dtype=np.float32), np.array([[0, 1, 2, 3]]))
    assert quads["positions"].dtype == np.float32 and quads["face_indices"].shape == (1, 4)
    assert "face_sizes" not in quads
    pair = mesh_to_arrays(positions, ([0, 1, 2], [3]), uvs=[[0, 0], [1, 0], [1, 1]],
                          normals=np.zeros((3, 3)), face_groups=[7])
    assert pair["uvs"].dtype == np.float32 and pair["normals"].dtype == np.float32
    with pytest.raises(ValueError):
        mesh_to_arrays(positions, [[0, -1, 2]])
    with pytest.raises(ValueError):
        mesh_to_arrays([[0, 0]], [[0, 0, 0]])


@pytest.mark.parametrize("use_numpy", [True, False])
def test_mesh_arrays_round_trip_through_frames(use_numpy):
    positions = np.random.default_rng(1).random((6, 3))
    faces = [[0, 1, 2], [2, 3, 4, 5]]
    data = encode_frame_bytes({"id": 1, "type": "ok"}, mesh_to_arrays(positions, faces))
    _, arrays = decode_frame(data, use_numpy=use_numpy)
    mesh = arrays_to_mesh(arrays)
    assert mesh.faces() == faces and mesh.vertex_count == 6 and mesh.face_count == 2
    assert np.array_equal(np.array(mesh.positions_list()), positions)
    # A [F, n] face_indices without face_sizes gets face_sizes derived.
    data = encode_frame_bytes({"id": 1, "type": "ok"},
                              mesh_to_arrays(positions, np.array([[0, 1, 2], [3, 4, 5]])))
    mesh = arrays_to_mesh(decode_frame(data, use_numpy=use_numpy)[1])
    assert mesh.faces() == [[0, 1, 2], [3, 4, 5]]


# ------------------------------------------------------------------------------------------
# Socket paths


def test_socket_path_rules(monkeypatch, tmp_path):
    xdg = tmp_path / "xdg"
    xdg.mkdir()
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(xdg))
    assert default_socket_path() == str(xdg / "tessd.sock")
    assert resolve_socket("work") == str(xdg / "work.sock")
    assert resolve_socket("./rel.sock") == "./rel.sock"
    assert resolve_socket("/abs/x") == "/abs/x"
    assert resolve_socket(None) == resolve_socket("") == default_socket_path()
    # XDG_RUNTIME_DIR that is not a directory: fall back to $TMPDIR/tessd-<uid>.
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path / "missing"))
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    expected_dir = tmp_path / ("tessd-%d" % os.getuid())
    assert default_socket_dir() == str(expected_dir)
    assert not expected_dir.exists()
    assert default_socket_path(create_dir=True) == str(expected_dir / "tessd.sock")
    assert stat.S_IMODE(expected_dir.stat().st_mode) == 0o700
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    monkeypatch.delenv("TMPDIR")
    assert default_socket_path() == "/tmp/tessd-%d/tessd.sock" % os.getuid()
