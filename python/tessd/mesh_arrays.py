"""Meshes as protocol arrays (docs/protocol.md, "Mesh arrays").

| name | dtype | shape |
|---|---|---|
| ``positions`` | f32 or f64 | [V, 3] |
| ``face_indices`` | u32 | [K] with ``face_sizes`` [F], or [F, n] |
| ``normals`` (+ ``normal_indices``) | f32 (u32) | [N, 3] ([K]); without indices [K, 3] |
| ``uvs`` (+ ``uv_indices``) | f32 (u32) | [T, 2] ([K]); without indices [K, 2] |
| ``crease_edges``, ``crease_values`` | u32, f32 | [E, 2], [E] |
| ``face_groups`` | u32 | [F] |

:func:`mesh_to_arrays` builds that dict from numpy arrays or plain Python sequences;
:func:`arrays_to_mesh` reads it back into a :class:`MeshArrays`.
"""

from __future__ import annotations

import array
from typing import Any, Dict, Iterator, List, Mapping, NamedTuple, Optional, Sequence, Tuple

from .arrays import INT_RANGE, ITEMSIZE, RawArray, TYPECODE, fit_integers, has_numpy, product

if has_numpy():
    import numpy as _np
else:  # pragma: no cover
    _np = None


def _is_ndarray(value: Any) -> bool:
    return _np is not None and isinstance(value, _np.ndarray)


def _flatten(rows: Sequence[Sequence[Any]], width: int, what: str) -> List[Any]:
    flat: List[Any] = []
    for i, row in enumerate(rows):
        if len(row) != width:
            raise ValueError("%s[%d] has %d components, expected %d" % (what, i, len(row), width))
        flat.extend(row)
    return flat


def _typed(value: Any, dtypes: Tuple[str, ...], width: Optional[int], what: str) -> Any:
    """``value`` as an array of one of ``dtypes`` (the first is the default for conversions).

    ``width`` is the required last dimension (None: 1-D). Numpy input stays numpy (converted
    only if its dtype is not allowed); lists become ``(dtype, shape, bytes)`` tuples.
    """
    if isinstance(value, RawArray):
        if value.dtype not in dtypes:
            raise TypeError("%s: dtype %s, expected %s" % (what, value.dtype, " or ".join(dtypes)))
        return value
    if _is_ndarray(value) or (_np is not None and not isinstance(value, array.array)):
        arr = _np.asarray(value)
        name = "%s%d" % (arr.dtype.kind, arr.dtype.itemsize * 8) if arr.dtype.kind in "uif" else ""
        if name not in dtypes:
            if dtypes[0].startswith("u") and arr.dtype.kind in "iu":
                arr = fit_integers(arr, what, dtypes[0])  # refuses what does not fit
            arr = arr.astype("<" + dtypes[0][0] + str(ITEMSIZE[dtypes[0]]))
        if width is None:
            arr = arr.reshape(-1)
        elif arr.ndim != 2 or arr.shape[1] != width:
            if arr.size == 0:
                arr = arr.reshape(0, width)
            else:
                raise ValueError("%s: shape %s, expected [N, %d]" % (what, list(arr.shape), width))
        return _np.ascontiguousarray(arr)
    if isinstance(value, array.array):
        flat = list(value)
    elif width is None:
        flat = list(value)
    else:
        flat = _flatten(value, width, what)
    dtype = dtypes[0]
    if dtype.startswith("u"):
        low, high = INT_RANGE[dtype]
        for i, v in enumerate(flat):
            if v < low or v > high:
                raise ValueError("%s[%d] is %d: %s" % (
                    what, i, v, "a negative index" if v < 0 else
                    "above %d, the largest %s" % (high, dtype)))
    data = array.array(TYPECODE[dtype], flat)
    count = len(flat) if width is None else len(flat) // width
    shape = (count,) if width is None else (count, width)
    return (dtype, shape, data.tobytes() if _little() else _swapped(data))


def _little() -> bool:
    import sys

    return sys.byteorder == "little"


def _swapped(data: array.array) -> bytes:  # pragma: no cover - big-endian only
    data = array.array(data.typecode, data)
    data.byteswap()
    return data.tobytes()


def _faces_arrays(faces: Any) -> Dict[str, Any]:
    """face_indices (and face_sizes) from a faces argument of any accepted form."""
    if isinstance(faces, tuple) and len(faces) == 2:
        indices, sizes = faces
        return {"face_indices": _typed(indices, ("u32",), None, "face_indices"),
                "face_sizes": _typed(sizes, ("u32",), None, "face_sizes")}
    if isinstance(faces, RawArray):
        if faces.ndim != 2:
            raise ValueError("a faces array must be [F, n]; pass (face_indices, face_sizes)")
        return {"face_indices": _typed(faces, ("u32",), None, "face_indices")}
    if _is_ndarray(faces):
        if faces.ndim != 2:
            raise ValueError("a faces array must be [F, n]; pass (face_indices, face_sizes)")
        arr = faces
        if arr.dtype != _np.dtype("<u4"):
            arr = fit_integers(arr, "faces", "u32")  # refuses what does not fit
            arr = arr.astype("<u4")
        return {"face_indices": _np.ascontiguousarray(arr)}
    # A sequence of polygons (lists of vertex indices, possibly of different sizes).
    sizes = [len(f) for f in faces]
    flat = [i for f in faces for i in f]
    return {"face_indices": _typed(flat, ("u32",), None, "faces"),
            "face_sizes": _typed(sizes, ("u32",), None, "face sizes")}


def mesh_to_arrays(positions: Any, faces: Any, normals: Any = None, uvs: Any = None, *,
                   normal_indices: Any = None, uv_indices: Any = None, crease_edges: Any = None,
                   crease_values: Any = None, face_groups: Any = None) -> Dict[str, Any]:
    """The protocol arrays of a mesh, ready for ``Client.call(..., arrays=...)``.

    - ``positions``: [V, 3] numpy array (f32 kept, f64 kept, other types become f64) or a
      sequence of ``(x, y, z)``.
    - ``faces``: a sequence of polygons (index lists, any sizes), a [F, n] integer array
      (all n-gons), or a ``(face_indices, face_sizes)`` pair.
    - ``normals`` [N, 3] and ``uvs`` [T, 2] are indexed by ``normal_indices`` / ``uv_indices``
      ([K], one per face corner) when given, else are per corner ([K, 3] / [K, 2]).
    - ``crease_edges`` [E, 2] with ``crease_values`` [E]; ``face_groups`` [F].
    """
    out: Dict[str, Any] = {"positions": _typed(positions, ("f64", "f32"), 3, "positions")}
    out.update(_faces_arrays(faces))
    if normals is not None:
        out["normals"] = _typed(normals, ("f32",), 3, "normals")
    if normal_indices is not None:
        out["normal_indices"] = _typed(normal_indices, ("u32",), None, "normal_indices")
    if uvs is not None:
        out["uvs"] = _typed(uvs, ("f32",), 2, "uvs")
    if uv_indices is not None:
        out["uv_indices"] = _typed(uv_indices, ("u32",), None, "uv_indices")
    if crease_edges is not None:
        out["crease_edges"] = _typed(crease_edges, ("u32",), 2, "crease_edges")
    if crease_values is not None:
        out["crease_values"] = _typed(crease_values, ("f32",), None, "crease_values")
    if face_groups is not None:
        out["face_groups"] = _typed(face_groups, ("u32",), None, "face_groups")
    return out


#: Mesh arrays the daemon reads as u32 (docs/protocol.md, "Mesh arrays").
U32_ARRAYS = frozenset({"face_indices", "face_sizes", "normal_indices", "uv_indices",
                        "crease_edges", "face_groups", "sharp_edges"})


def prepare_arrays(arrays: Any) -> Optional[List[Tuple[str, Any]]]:
    """The arrays of a request as ``(name, array)`` pairs, the integer mesh arrays
    (:data:`U32_ARRAYS`) of another integer type (numpy's default int64, int32, uint64,
    int16...) converted to the u32 the daemon reads when every value fits; ``ValueError``
    naming the array, the value, its flat index and why (negative, too large) when one does
    not.

    Everything else goes as given (float arrays too: the daemon's dtype errors name them).
    ``None`` stays ``None``; the caller's mapping is not changed.
    """
    if arrays is None:
        return None
    items = list(arrays.items()) if isinstance(arrays, Mapping) else list(arrays)
    return [(name, fit_integers(value, name, "u32") if name in U32_ARRAYS else value)
            for name, value in items]


class MeshArrays(NamedTuple):
    """A mesh received as arrays (numpy arrays or RawArrays; absent ones are None).

    ``face_sizes`` is always present: derived from a [F, n] ``face_indices`` when the reply
    did not carry it (``face_indices`` is then flattened to [K]).
    """

    positions: Any
    face_indices: Any
    face_sizes: Any
    normals: Any = None
    normal_indices: Any = None
    uvs: Any = None
    uv_indices: Any = None
    crease_edges: Any = None
    crease_values: Any = None
    face_groups: Any = None

    @property
    def vertex_count(self) -> int:
        """Number of stored vertices."""
        return int(self.positions.shape[0])

    @property
    def face_count(self) -> int:
        """Number of faces."""
        return int(self.face_sizes.shape[0])

    def faces(self) -> List[List[int]]:
        """The faces as lists of vertex indices."""
        return list(iter_faces(self.face_indices, self.face_sizes))

    def positions_list(self) -> List[List[float]]:
        """The positions as ``[[x, y, z], ...]``."""
        return self.positions.tolist()


def _as_list(a: Any) -> List[Any]:
    if isinstance(a, RawArray):
        return a.to_array().tolist()
    if _is_ndarray(a):
        return a.reshape(-1).tolist()
    return list(a)


def iter_faces(face_indices: Any, face_sizes: Any) -> Iterator[List[int]]:
    """Yields each face's vertex indices from flat ``face_indices`` and ``face_sizes``."""
    flat = _as_list(face_indices)
    start = 0
    for n in _as_list(face_sizes):
        yield flat[start : start + n]
        start += n
    if start != len(flat):
        raise ValueError("face_sizes sum to %d but there are %d face indices" % (start, len(flat)))


def arrays_to_mesh(arrays: Dict[str, Any]) -> MeshArrays:
    """A :class:`MeshArrays` from a reply's arrays (``positions`` and ``face_indices`` required)."""
    for required in ("positions", "face_indices"):
        if required not in arrays:
            raise KeyError("the arrays hold no %r" % required)
    indices = arrays["face_indices"]
    sizes = arrays.get("face_sizes")
    if sizes is None:
        shape = tuple(indices.shape)
        if len(shape) != 2:
            raise ValueError("1-D face_indices without face_sizes")
        f, n = shape
        if _is_ndarray(indices):
            sizes = _np.full(f, n, dtype="<u4")
            indices = indices.reshape(-1)
        else:
            sizes = RawArray("u32", (f,), array.array(TYPECODE["u32"], [n] * f).tobytes())
            indices = RawArray("u32", (product(shape),), indices.data)
    names = MeshArrays._fields[3:]
    return MeshArrays(arrays["positions"], indices, sizes, *(arrays.get(k) for k in names))


__all__ = ["MeshArrays", "U32_ARRAYS", "arrays_to_mesh", "iter_faces", "mesh_to_arrays",
           "prepare_arrays"]
