"""Encoding and decoding of wire-protocol frames (docs/protocol.md, version 1).

A frame is a 24-byte header (magic ``TSSD``, version, flags, ``json_len``, reserved,
``payload_len``), a UTF-8 JSON object, and a binary payload holding the arrays that the
object's ``arrays`` table describes. Everything here validates as the daemon does and raises
:class:`ProtocolError` (``code`` is ``invalid_frame`` or ``too_large``) on bad input.

Sending avoids copies: :func:`encode_frame` returns a list of buffers (header and JSON, then
each array and its alignment padding) to be written one after the other. Receiving reads the
payload into one preallocated buffer and returns arrays that are views of it.
"""

from __future__ import annotations

import json
import struct
from typing import Any, Callable, Dict, Iterable, List, Mapping, NamedTuple, Optional, Tuple, Union

from . import arrays as _arrays
from .arrays import ITEMSIZE, WireArray, from_wire, has_numpy, product, to_wire
from .errors import Error

MAGIC = b"TSSD"
VERSION = 1
HEADER_SIZE = 24
#: Largest JSON document accepted (16 MiB).
MAX_JSON_LEN = 16 * 1024 * 1024
#: The daemon's default ``--max-payload`` (4 GiB).
DEFAULT_MAX_PAYLOAD = 4 * 1024 ** 3
#: Arrays start at offsets that are multiples of this.
ALIGNMENT = 8

_HEADER = struct.Struct("<4sHHIIQ")
_ZEROS = bytes(ALIGNMENT)

ArraysArg = Union[None, Mapping[str, Any], Iterable[Tuple[str, Any]]]


class ProtocolError(Error):
    """Bytes that are not a valid frame (a :class:`tessd.Error`).

    ``code`` is the protocol error code the daemon would use: ``invalid_frame`` or
    ``too_large``.
    """

    def __init__(self, message: str, code: str = "invalid_frame"):
        super().__init__(message)
        self.code = code
        self.message = message


class Header(NamedTuple):
    """The two sizes a valid header declares."""

    json_len: int
    payload_len: int


class ArraySpec(NamedTuple):
    """One validated entry of a frame's array table."""

    name: str
    dtype: str
    shape: Tuple[int, ...]
    offset: int
    length: int


# --------------------------------------------------------------------------------------------
# Header


def pack_header(json_len: int, payload_len: int, *, magic: bytes = MAGIC, version: int = VERSION,
                flags: int = 0, reserved: int = 0) -> bytes:
    """The 24-byte header for the given sizes (the keyword fields exist to build bad frames)."""
    return _HEADER.pack(magic, version, flags, json_len, reserved, payload_len)


def unpack_header(data: Any, *, max_json: int = MAX_JSON_LEN,
                  max_payload: Optional[int] = DEFAULT_MAX_PAYLOAD) -> Header:
    """Parses and validates a 24-byte header.

    Checks the magic, version, flags and reserved field (``invalid_frame``), ``json_len >= 1``
    (``invalid_frame``), and the size limits (``too_large``) before anything is allocated.
    ``max_payload=None`` means no payload limit.
    """
    if len(data) < HEADER_SIZE:
        raise ProtocolError("short header: %d of %d bytes" % (len(data), HEADER_SIZE))
    magic, version, flags, json_len, reserved, payload_len = _HEADER.unpack_from(data, 0)
    if magic != MAGIC:
        raise ProtocolError("bad magic %r (expected %r)" % (bytes(magic), MAGIC))
    if version != VERSION:
        raise ProtocolError("unsupported protocol version %d (expected %d)" % (version, VERSION))
    if flags != 0:
        raise ProtocolError("non-zero flags 0x%04x" % flags)
    if reserved != 0:
        raise ProtocolError("non-zero reserved field 0x%08x" % reserved)
    if json_len == 0:
        raise ProtocolError("json_len is 0 (a frame holds a JSON object)")
    if json_len > max_json:
        raise ProtocolError("json_len %d exceeds the limit of %d bytes" % (json_len, max_json),
                            "too_large")
    if max_payload is not None and payload_len > max_payload:
        raise ProtocolError(
            "payload_len %d exceeds the limit of %d bytes" % (payload_len, max_payload), "too_large"
        )
    return Header(json_len, payload_len)


# --------------------------------------------------------------------------------------------
# JSON and array table


def parse_json(data: Any) -> Dict[str, Any]:
    """Decodes the JSON part of a frame, which must be a UTF-8 JSON object."""
    try:
        text = bytes(data).decode("utf-8")
    except UnicodeDecodeError as e:
        raise ProtocolError("JSON is not valid UTF-8: %s" % e) from None
    try:
        obj = json.loads(text, parse_constant=_reject_constant)
    except ValueError as e:
        raise ProtocolError("invalid JSON: %s" % e) from None
    if not isinstance(obj, dict):
        raise ProtocolError("JSON is a %s, not an object" % _json_type(obj))
    return obj


def _reject_constant(name: str) -> Any:
    raise ValueError("%s is not valid JSON" % name)


def _json_type(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "array"
    return "object"


def _is_uint(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def parse_array_table(table: Any, payload_len: int) -> List[ArraySpec]:
    """Validates a frame's ``arrays`` table against its payload length.

    Each entry must be an object with a string ``name`` (unique), a known ``dtype``, a
    ``shape`` list of unsigned integers, an ``offset`` that is a multiple of 8, and a
    ``length`` equal to the element count times the item size, with
    ``offset + length <= payload_len``. Arrays must not overlap.
    """
    if table is None:
        return []
    if not isinstance(table, list):
        raise ProtocolError("'arrays' is a %s, not a list" % _json_type(table))
    specs = []
    names = set()
    for i, entry in enumerate(table):
        where = "arrays[%d]" % i
        if not isinstance(entry, dict):
            raise ProtocolError("%s is a %s, not an object" % (where, _json_type(entry)))
        for key in ("name", "dtype", "shape", "offset", "length"):
            if key not in entry:
                raise ProtocolError("%s has no '%s'" % (where, key))
        name, dtype, shape = entry["name"], entry["dtype"], entry["shape"]
        offset, length = entry["offset"], entry["length"]
        if not isinstance(name, str):
            raise ProtocolError("%s: 'name' is not a string" % where)
        where = "array %r" % name
        if name in names:
            raise ProtocolError("duplicate array name %r" % name)
        names.add(name)
        if not isinstance(dtype, str) or dtype not in ITEMSIZE:
            raise ProtocolError("%s: unknown dtype %r" % (where, dtype))
        if not isinstance(shape, list) or not all(_is_uint(d) for d in shape):
            raise ProtocolError("%s: 'shape' is not a list of unsigned integers" % where)
        if not _is_uint(offset):
            raise ProtocolError("%s: 'offset' is not an unsigned integer" % where)
        if not _is_uint(length):
            raise ProtocolError("%s: 'length' is not an unsigned integer" % where)
        if offset % ALIGNMENT:
            raise ProtocolError("%s: offset %d is not a multiple of %d" % (where, offset, ALIGNMENT))
        expected = product(shape) * ITEMSIZE[dtype]
        if length != expected:
            raise ProtocolError(
                "%s: length %d but shape %s of %s needs %d bytes"
                % (where, length, shape, dtype, expected)
            )
        if offset + length > payload_len:
            raise ProtocolError(
                "%s: bytes %d..%d lie outside the payload of %d bytes"
                % (where, offset, offset + length, payload_len)
            )
        specs.append(ArraySpec(name, dtype, tuple(shape), offset, length))
    ordered = sorted((s for s in specs if s.length), key=lambda s: s.offset)
    for a, b in zip(ordered, ordered[1:]):
        if a.offset + a.length > b.offset:
            raise ProtocolError("arrays %r and %r overlap" % (a.name, b.name))
    return specs


def arrays_from_payload(specs: List[ArraySpec], payload: Any,
                        use_numpy: Optional[bool] = None) -> Dict[str, Any]:
    """Views of the validated arrays in ``payload`` (numpy arrays, or RawArray objects)."""
    if use_numpy is None:
        use_numpy = has_numpy()
    return {s.name: from_wire(s.dtype, s.shape, payload, s.offset, use_numpy) for s in specs}


# --------------------------------------------------------------------------------------------
# Encoding


def _items(arrays: ArraysArg) -> List[Tuple[str, Any]]:
    if arrays is None:
        return []
    if isinstance(arrays, Mapping):
        return list(arrays.items())
    return list(arrays)


def layout_arrays(arrays: ArraysArg) -> Tuple[List[Dict[str, Any]], List[Any], int]:
    """Lays out arrays in a payload.

    Returns ``(table, pieces, payload_len)``: the ``arrays`` table for the JSON object, the
    buffers making up the payload in order (array data and zero padding; nothing copied),
    and the payload length.
    """
    table = []
    pieces: List[Any] = []
    offset = 0
    seen = set()
    for name, value in _items(arrays):
        if not isinstance(name, str):
            raise TypeError("array names must be strings, got %r" % (name,))
        if name in seen:
            raise ValueError("duplicate array name %r" % name)
        seen.add(name)
        wire = to_wire(value, name)
        pad = (-offset) % ALIGNMENT
        if pad:
            pieces.append(_ZEROS[:pad])
            offset += pad
        table.append({"name": name, "dtype": wire.dtype, "shape": list(wire.shape),
                      "offset": offset, "length": wire.nbytes})
        if wire.nbytes:
            pieces.append(wire.data)
        offset += wire.nbytes
    return table, pieces, offset


def encode_json(obj: Mapping[str, Any]) -> bytes:
    """Compact UTF-8 JSON for a frame (NaN and infinities are rejected: JSON has none)."""
    return json.dumps(obj, separators=(",", ":"), ensure_ascii=False, allow_nan=False).encode()


def encode_frame(message: Mapping[str, Any], arrays: ArraysArg = None) -> List[Any]:
    """Encodes a frame as a list of buffers to write in order (see :func:`layout_arrays`).

    ``message`` is the JSON object without its ``arrays`` member, which is filled in from
    ``arrays`` (a mapping or a list of ``(name, array)`` pairs) when any are given.
    """
    table, pieces, payload_len = layout_arrays(arrays)
    obj = dict(message)
    if table:
        obj["arrays"] = table
    body = encode_json(obj)
    if len(body) > MAX_JSON_LEN:
        raise ProtocolError("JSON of %d bytes exceeds the %d-byte limit" % (len(body), MAX_JSON_LEN),
                            "too_large")
    return [pack_header(len(body), payload_len) + body] + pieces


def encode_frame_bytes(message: Mapping[str, Any], arrays: ArraysArg = None) -> bytes:
    """Encodes a frame into one ``bytes`` object (convenient for small frames and tests)."""
    return b"".join(bytes(p) for p in encode_frame(message, arrays))


# --------------------------------------------------------------------------------------------
# Decoding


def decode_frame(data: Any, *, use_numpy: Optional[bool] = None,
                 max_payload: Optional[int] = DEFAULT_MAX_PAYLOAD) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """Decodes exactly one complete frame from ``data``.

    Returns ``(message, arrays)`` where arrays are views of ``data``. Raises
    :class:`ProtocolError` for any invalid or truncated frame, or trailing bytes.
    """
    view = memoryview(data)
    if view.format != "B" or view.ndim != 1:
        view = view.cast("B")
    header = unpack_header(view, max_payload=max_payload)
    end_json = HEADER_SIZE + header.json_len
    end = end_json + header.payload_len
    if len(view) < end_json:
        raise ProtocolError("truncated JSON: %d of %d bytes" % (len(view) - HEADER_SIZE, header.json_len))
    if len(view) < end:
        raise ProtocolError("truncated payload: %d of %d bytes" % (len(view) - end_json, header.payload_len))
    if len(view) > end:
        raise ProtocolError("%d bytes after the end of the frame" % (len(view) - end))
    message = parse_json(view[HEADER_SIZE:end_json])
    specs = parse_array_table(message.get("arrays"), header.payload_len)
    return message, arrays_from_payload(specs, view[end_json:end], use_numpy)


def _read_exactly(recv_into: Callable[[memoryview], int], buf: Any, what: str,
                  allow_eof: bool = False) -> bool:
    """Fills ``buf`` from ``recv_into``; False on EOF before the first byte if ``allow_eof``."""
    view = memoryview(buf)
    if view.format != "B" or view.ndim != 1:
        view = view.cast("B")
    total = len(view)
    got = 0
    while got < total:
        n = recv_into(view[got:])
        if not n:
            if got == 0 and allow_eof:
                return False
            raise ProtocolError("connection closed in the middle of the %s (%d of %d bytes)"
                                % (what, got, total))
        got += n
    return True


def _alloc_payload(n: int, use_numpy: bool) -> Any:
    if use_numpy and n:
        # Uninitialized: recv_into overwrites all of it, and big meshes skip a memset.
        return _arrays._np.empty(n, dtype=_arrays._np.uint8)
    return bytearray(n)


def read_frame(recv_into: Callable[[memoryview], int], *, use_numpy: Optional[bool] = None,
               max_payload: Optional[int] = None) -> Optional[Tuple[Dict[str, Any], Dict[str, Any]]]:
    """Reads one frame from a stream.

    ``recv_into(view)`` fills a prefix of ``view`` and returns the byte count (0 at EOF), like
    ``socket.recv_into``. Returns ``(message, arrays)`` with arrays viewing one buffer
    allocated for the whole payload, or ``None`` on EOF at a frame boundary. Raises
    :class:`ProtocolError` for invalid frames or EOF inside a frame.
    """
    if use_numpy is None:
        use_numpy = has_numpy()
    header_buf = bytearray(HEADER_SIZE)
    if not _read_exactly(recv_into, header_buf, "header", allow_eof=True):
        return None
    header = unpack_header(header_buf, max_payload=max_payload)
    json_buf = bytearray(header.json_len)
    _read_exactly(recv_into, json_buf, "JSON")
    message = parse_json(json_buf)
    # Validate the table before allocating or reading the payload.
    specs = parse_array_table(message.get("arrays"), header.payload_len)
    payload = _alloc_payload(header.payload_len, use_numpy)
    _read_exactly(recv_into, payload, "payload")
    return message, arrays_from_payload(specs, payload, use_numpy)


__all__ = [
    "ALIGNMENT", "ArraySpec", "DEFAULT_MAX_PAYLOAD", "HEADER_SIZE", "Header", "MAGIC",
    "MAX_JSON_LEN", "ProtocolError", "VERSION", "WireArray", "arrays_from_payload",
    "decode_frame", "encode_frame", "encode_frame_bytes", "encode_json", "layout_arrays",
    "pack_header", "parse_array_table", "parse_json", "read_frame", "unpack_header",
]
