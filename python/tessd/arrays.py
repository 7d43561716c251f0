"""Typed arrays as the wire protocol carries them.

The protocol knows eight little-endian element types (``u8 u16 u32 u64 i32 i64 f32 f64``).
This module converts what a caller hands over (numpy arrays, ``array.array``, ``(dtype,
shape, bytes)`` tuples, :class:`RawArray`) into a :class:`WireArray` (dtype, shape and a flat
byte view, no copy where the input already has the right layout), and turns received bytes
back into numpy arrays when numpy is importable, else into :class:`RawArray` objects.
"""

from __future__ import annotations

import array
import sys
from typing import Any, Iterable, List, NamedTuple, Optional, Sequence, Tuple

try:  # numpy is optional: used when present, never required.
    import numpy as _np
except ImportError:  # pragma: no cover - exercised only where numpy is missing
    _np = None

#: Item size in bytes of each protocol dtype.
ITEMSIZE = {"u8": 1, "u16": 2, "u32": 4, "u64": 8, "i32": 4, "i64": 8, "f32": 4, "f64": 8}

#: Every dtype name the protocol accepts, in a stable order.
DTYPES = tuple(ITEMSIZE)

_LITTLE = sys.byteorder == "little"


def _typecode(kind: str, size: int) -> str:
    """The ``array.array`` typecode with the given kind ('u', 'i', 'f') and item size."""
    candidates = {"u": "BHILQ", "i": "bhilq", "f": "fd"}[kind]
    for code in candidates:
        if array.array(code).itemsize == size:
            return code
    raise RuntimeError("no array.array typecode for %s%d" % (kind, size * 8))  # pragma: no cover


#: ``array.array`` / ``memoryview`` typecode of each protocol dtype on this platform.
TYPECODE = {name: _typecode(name[0], ITEMSIZE[name]) for name in DTYPES}

_TYPECODE_TO_DTYPE = {}
for _name, _code in TYPECODE.items():
    _TYPECODE_TO_DTYPE[_code] = _name
# Other typecodes that have the same size as a protocol dtype ('l' and 'L' are 4 or 8 bytes).
for _code in "bBhHiIlLqQfd":
    _size = array.array(_code).itemsize
    _kind = "f" if _code in "fd" else ("u" if _code.isupper() else "i")
    _candidate = "%s%d" % (_kind, _size * 8)
    if _candidate in ITEMSIZE:
        _TYPECODE_TO_DTYPE.setdefault(_code, _candidate)


def has_numpy() -> bool:
    """Whether numpy could be imported (received arrays are numpy arrays then)."""
    return _np is not None


def product(shape: Iterable[int]) -> int:
    """The number of elements of an array of this shape (1 for ``()``)."""
    n = 1
    for d in shape:
        n *= d
    return n


class WireArray(NamedTuple):
    """An array ready to be sent: protocol dtype, shape and a flat C-order byte view.

    ``data`` is a ``memoryview`` of format ``'B'`` holding exactly
    ``product(shape) * ITEMSIZE[dtype]`` little-endian bytes.
    """

    dtype: str
    shape: Tuple[int, ...]
    data: memoryview

    @property
    def nbytes(self) -> int:
        """Length of the data in bytes."""
        return self.data.nbytes


class RawArray:
    """A received array when numpy is not available (or not wanted).

    ``dtype`` is the protocol dtype name, ``shape`` a tuple, ``data`` a flat ``memoryview`` of
    format ``'B'`` over the received little-endian bytes (not a copy).
    """

    __slots__ = ("dtype", "shape", "data")

    def __init__(self, dtype: str, shape: Sequence[int], data: Any):
        if dtype not in ITEMSIZE:
            raise TypeError("unknown dtype %r (expected one of %s)" % (dtype, ", ".join(DTYPES)))
        self.dtype = dtype
        self.shape = tuple(int(d) for d in shape)
        view = memoryview(data)
        if view.format != "B" or view.ndim != 1:
            view = view.cast("B")
        expected = product(self.shape) * ITEMSIZE[dtype]
        if view.nbytes != expected:
            raise ValueError(
                "%s array of shape %s needs %d bytes, got %d"
                % (dtype, list(self.shape), expected, view.nbytes)
            )
        self.data = view

    @property
    def itemsize(self) -> int:
        """Bytes per element."""
        return ITEMSIZE[self.dtype]

    @property
    def nbytes(self) -> int:
        """Total bytes."""
        return self.data.nbytes

    @property
    def size(self) -> int:
        """Number of elements."""
        return product(self.shape)

    @property
    def ndim(self) -> int:
        """Number of dimensions."""
        return len(self.shape)

    def __len__(self) -> int:
        if not self.shape:
            raise TypeError("len() of a 0-d array")
        return self.shape[0]

    def to_array(self) -> array.array:
        """A flat ``array.array`` copy of the elements, in native byte order."""
        out = array.array(TYPECODE[self.dtype])
        out.frombytes(self.data)
        if not _LITTLE:  # pragma: no cover - big-endian hosts only
            out.byteswap()
        return out

    def flat(self) -> memoryview:
        """A flat typed ``memoryview`` of the elements, without copying.

        Elements are read in native order, so this is right on little-endian hosts only (all
        platforms tessd supports); use :meth:`to_array` to be portable.
        """
        return self.data.cast(TYPECODE[self.dtype])

    def tolist(self) -> Any:
        """The elements as (nested) Python lists, like ``numpy.ndarray.tolist``."""
        flat = self.to_array().tolist()
        if not self.shape:
            return flat[0]
        return _nest(flat, self.shape)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RawArray):
            return NotImplemented
        return (
            self.dtype == other.dtype
            and self.shape == other.shape
            and self.data.tobytes() == other.data.tobytes()
        )

    def __repr__(self) -> str:
        return "RawArray(%r, %r, <%d bytes>)" % (self.dtype, list(self.shape), self.nbytes)


def _nest(flat: List[Any], shape: Tuple[int, ...]) -> List[Any]:
    """Splits a flat list into nested lists of the given shape (C order)."""
    if len(shape) == 1:
        return flat
    step = product(shape[1:])
    return [_nest(flat[i * step : (i + 1) * step], shape[1:]) for i in range(shape[0])]


def _numpy_dtype_name(dt: Any) -> Optional[str]:
    kind = {"u": "u", "i": "i", "f": "f", "b": None}.get(dt.kind)
    if kind is None:
        return None
    name = "%s%d" % (kind, dt.itemsize * 8)
    return name if name in ITEMSIZE else None


def to_wire(value: Any, name: str = "array") -> WireArray:
    """Converts an array to send into a :class:`WireArray`.

    Accepts a numpy array (any dtype with a protocol equivalent; copied only when not
    C-contiguous or not little-endian), an ``array.array`` (1-D), a :class:`RawArray`, a
    :class:`WireArray`, or a ``(dtype, shape, data)`` tuple where ``data`` is any bytes-like
    object of exactly the right length. Raises ``TypeError``/``ValueError`` otherwise.
    """
    if isinstance(value, WireArray):
        return value
    if isinstance(value, RawArray):
        return WireArray(value.dtype, value.shape, value.data)
    if _np is not None and isinstance(value, _np.ndarray):
        dtype = _numpy_dtype_name(value.dtype)
        if dtype is None:
            raise TypeError(
                "array %r: numpy dtype %s has no protocol equivalent (use one of %s)"
                % (name, value.dtype, ", ".join(DTYPES))
            )
        arr = value
        if arr.dtype.byteorder == ">" or (arr.dtype.byteorder == "=" and not _LITTLE):
            arr = arr.astype(arr.dtype.newbyteorder("<"))
        arr = _np.ascontiguousarray(arr)
        data = memoryview(arr.reshape(-1).view(_np.uint8))
        return WireArray(dtype, tuple(int(d) for d in value.shape), data)
    if isinstance(value, array.array):
        dtype = _TYPECODE_TO_DTYPE.get(value.typecode)
        if dtype is None:
            raise TypeError(
                "array %r: array.array typecode %r has no protocol equivalent"
                % (name, value.typecode)
            )
        if not _LITTLE:  # pragma: no cover - big-endian hosts only
            value = array.array(value.typecode, value)
            value.byteswap()
        return WireArray(dtype, (len(value),), memoryview(value).cast("B"))
    if isinstance(value, tuple) and len(value) == 3:
        dtype, shape, data = value
        if dtype not in ITEMSIZE:
            raise TypeError(
                "array %r: unknown dtype %r (expected one of %s)" % (name, dtype, ", ".join(DTYPES))
            )
        if isinstance(shape, int):
            shape = (shape,)
        shape = tuple(int(d) for d in shape)
        if any(d < 0 for d in shape):
            raise ValueError("array %r: negative dimension in shape %s" % (name, list(shape)))
        view = memoryview(data)
        if view.format != "B" or view.ndim != 1:
            view = view.cast("B")
        expected = product(shape) * ITEMSIZE[dtype]
        if view.nbytes != expected:
            raise ValueError(
                "array %r: %s of shape %s needs %d bytes, got %d"
                % (name, dtype, list(shape), expected, view.nbytes)
            )
        return WireArray(dtype, shape, view)
    raise TypeError(
        "array %r: cannot send %s (use a numpy array, array.array, RawArray or "
        "a (dtype, shape, bytes) tuple)" % (name, type(value).__name__)
    )


#: Smallest and largest value of each integer protocol dtype.
INT_RANGE = {"u8": (0, 2 ** 8 - 1), "u16": (0, 2 ** 16 - 1), "u32": (0, 2 ** 32 - 1),
             "u64": (0, 2 ** 64 - 1), "i32": (-2 ** 31, 2 ** 31 - 1),
             "i64": (-2 ** 63, 2 ** 63 - 1)}


def dtype_of(value: Any) -> Optional[str]:
    """The protocol dtype ``value`` would be sent as (see :func:`to_wire`), or None when it
    has none (then :func:`to_wire` refuses it)."""
    if isinstance(value, (WireArray, RawArray)):
        return value.dtype
    if _np is not None and isinstance(value, _np.ndarray):
        return _numpy_dtype_name(value.dtype)
    if isinstance(value, array.array):
        return _TYPECODE_TO_DTYPE.get(value.typecode)
    if isinstance(value, tuple) and len(value) == 3 and value[0] in ITEMSIZE:
        return value[0]
    return None


def _out_of_range(name: str, source: str, dtype: str, value: int, index: int) -> ValueError:
    low, high = INT_RANGE[dtype]
    why = ("is negative" if value < 0 and low == 0 else
           "is below %d, the smallest %s" % (low, dtype) if value < low else
           "is above %d, the largest %s" % (high, dtype))
    return ValueError("array %r (%s) holds %d at flat index %d, which %s; the daemon reads %r "
                      "as %s" % (name, source, value, index, why, name, dtype))


def fit_integers(value: Any, name: str, dtype: str) -> Any:
    """``value``, an integer array of another dtype, converted to the integer ``dtype`` when
    every element fits (numpy's default int64 face indices become u32, for instance).

    Raises ``ValueError`` naming the array, the first element that does not fit, its flat
    index and why (negative, or above the largest ``dtype``). Anything else (already
    ``dtype``, a float array, something :func:`to_wire` refuses) is returned unchanged.
    """
    if dtype not in INT_RANGE:
        return value
    low, high = INT_RANGE[dtype]
    if _np is not None and isinstance(value, _np.ndarray):
        # Any numpy integer type, also those the protocol lacks (int8, int16).
        source = "%s%d" % (value.dtype.kind, value.dtype.itemsize * 8)
        if value.dtype.kind not in "iu" or source == dtype:
            return value
        if value.size:
            flat = value.reshape(-1)
            i_min, i_max = int(flat.argmin()), int(flat.argmax())
            if int(flat[i_min]) < low:
                raise _out_of_range(name, source, dtype, int(flat[i_min]), i_min)
            if int(flat[i_max]) > high:
                raise _out_of_range(name, source, dtype, int(flat[i_max]), i_max)
        return _np.ascontiguousarray(value.astype("<%s%d" % (dtype[0], ITEMSIZE[dtype])))
    source = dtype_of(value)
    if source is None or source == dtype or source[0] not in "ui":
        return value
    wire = to_wire(value, name)
    values = wire.data.cast(TYPECODE[source]).tolist() if _LITTLE else \
        RawArray(source, wire.shape, wire.data).to_array().tolist()
    for i, v in enumerate(values):
        if v < low or v > high:
            raise _out_of_range(name, source, dtype, v, i)
    out = array.array(TYPECODE[dtype], values)
    if not _LITTLE:  # pragma: no cover - big-endian hosts only
        out.byteswap()
    return (dtype, wire.shape, out.tobytes())


def from_wire(dtype: str, shape: Sequence[int], buffer: Any, offset: int, use_numpy: bool) -> Any:
    """An array viewing ``buffer[offset:]`` (no copy): numpy when ``use_numpy``, else RawArray.

    The caller has already checked that the bytes are in range.
    """
    count = product(shape)
    nbytes = count * ITEMSIZE[dtype]
    if use_numpy:
        if _np is None:
            raise RuntimeError("numpy is not available")
        flat = _np.frombuffer(buffer, dtype=_np.dtype("<" + dtype[0] + str(ITEMSIZE[dtype])),
                              count=count, offset=offset)
        return flat.reshape(tuple(shape))
    view = memoryview(buffer)
    if view.format != "B" or view.ndim != 1:
        view = view.cast("B")
    return RawArray(dtype, shape, view[offset : offset + nbytes])
