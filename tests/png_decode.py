"""The tests' PNG decoder (zlib and the five row filters, independent of tessd and of PIL), for
8-bit RGBA, non-interlaced images: what tessd writes. Rows with the None, Sub and Up filters are
undone with numpy, Average and Paeth rows byte by byte (on Python lists, much faster than
indexing numpy arrays element by element: the demo's 1280x720 pictures decode in seconds)."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np


def decode_png(data: bytes) -> np.ndarray:
    """An 8-bit RGBA, non-interlaced PNG's bytes as a uint8 array [H, W, 4]."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
    w, h, depth, color, _, _, interlace = header
    assert (depth, color, interlace) == (8, 6, 0), header
    stride, bpp = 4 * w, 4
    rows = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, stride + 1)
    out = np.zeros((h, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int64)
    for y in range(h):
        f, line = rows[y, 0], rows[y, 1:].astype(np.int64)
        if f == 0:
            cur = line
        elif f == 1:
            cur = np.cumsum(line.reshape(w, bpp), axis=0).reshape(stride) & 0xFF
        elif f == 2:
            cur = (line + prev) & 0xFF
        else:
            assert f in (3, 4), f
            raw, up, c = line.tolist(), prev.tolist(), [0] * stride
            for x in range(stride):
                a = c[x - bpp] if x >= bpp else 0
                b = up[x]
                if f == 3:
                    p = (a + b) // 2
                else:
                    d = up[x - bpp] if x >= bpp else 0
                    pa, pb, pc = abs(b - d), abs(a - d), abs(a + b - 2 * d)
                    p = a if pa <= pb and pa <= pc else (b if pb <= pc else d)
                c[x] = (raw[x] + p) & 0xFF
            cur = np.array(c, dtype=np.int64)
        out[y] = cur
        prev = cur
    return out.reshape(h, w, 4)


def read_png(path: Path) -> np.ndarray:
    """The PNG file at `path` as a uint8 array [H, W, 4] (see `decode_png`)."""
    return decode_png(Path(path).read_bytes())
