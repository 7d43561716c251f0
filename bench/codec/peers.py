#!/usr/bin/env python3
"""The peers of the codec benchmark (bench/run_codec.sh): Draco and meshoptimizer's codecs on
the same quantised meshes as `tessd compress`, plus the mesh loading, quantisation, lossless
checks and distances that bench/codec/run_codec.py shares with them.

    peers.py run --mesh PATH[,PATH...] [--bits 12,16] [--jsonl OUT] [--budget 1.0]
    peers.py one --mesh PATH --bits P --peer draco-10|draco-7|meshopt|load [--budget 1.0]
                 (child: one peer on one mesh, prints a JSON list of rows)

Each (mesh, p, peer) runs in a fresh child process (`one`); its whole peak RSS (KiB, from GNU
time, see run_child_rss: interpreter, libraries, mesh parsing) is `peak_rss_kib`, that of a
`load` child (imports + mesh loading + quantisation only) `baseline_rss_kib`. The codec's own
memory is `encode_peak_kib` / `decode_peak_kib`: the growth of the peak resident set (VmHWM,
reset through /proc/self/clear_refs after a heap trim) over the resident set before one untimed
encode / decode call, input arrays already built. Times are `time.perf_counter` medians over
repeats: at least 3, at most 25, until `--budget` seconds are spent.

Conventions (the same as core/codec/src/quantize.rs and the paper 003 §5.1):
  * Loading: positions and faces only, in file order; every vertex record counts (unreferenced
    ones too: `input_vertices`), polygons are fan-triangulated from their first corner
    (`input_triangles`). STL facets are merged on exactly equal positions.
  * Quantisation to p bits per coordinate in the cubic bounding box of *all* input vertices:
    origin = bbox min, step = largest side / (2^p - 1), q = floor((x - origin) / step + 0.5)
    clamped to [0, 2^p - 1] (round half away from zero, like Rust's f64::round); dequantised
    x' = origin + q * step. Draco's own quantiser (quantization_bits=p) is the same grid (its
    range is the largest side and its max quantised value 2^p - 1), but it computes in float32;
    it is given the grid integers (see draco_rows).
  * bits_per_vertex = 8 * bytes / input_vertices for every codec (the paper's Table 2 and
    `tessd compress`'s definition), even though Draco and meshopt drop unreferenced vertices.
  * Lossless check of a decoded mesh: the set of quantised positions of its vertices equals
    that of the referenced input vertices (and, where the decoder keeps isolated points, of all
    input vertices), and the set of its oriented triangles over quantised positions (rotated to
    start at the smallest key, triangles whose corners collapse dropped) equals the input's.
  * Geometric error of a decoded vertex set: for each referenced input vertex, the distance to
    the decoded vertex with the same grid key (else to the nearest decoded vertex, KD-tree);
    max and RMS, in model units and relative to the largest bbox side.

meshoptimizer: the `meshopt` wheel (a binding of meshoptimizer 1.3's encoder / decoder). The
pipeline is the one its README recommends: optimizeVertexCache, then optimizeVertexFetch
(remap; drops unreferenced vertices), positions as 4 x uint16 (p <= 16; the 4th, 0, pads a row
to the codec's multiple of 4 bytes, as gltfpack does; 3 x uint32 above 16 bits),
encodeVertexBuffer and encodeIndexBuffer. The vertex codec runs as its README recommends for the
best ratio: version 1 (encodeVertexVersion(1)), level 3 (`meshopt`, the table's column); raw
rows also have v1 level 2 (`-v1l2`) and v0 level 2 (`-v0`, what glTF's EXT_meshopt_compression
stores). Then the two streams, concatenated, through zstd (level 19) and deflate (zlib level 9),
the general-purpose compressors its docs recommend on top.

Run with /work/main/.venv-bench/bin/python.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

# ---------------------------------------------------------------------------------------------
# Loading (positions and faces only)


def _fan(polys):
    """Fan-triangulates a list of index lists; returns (triangles (m, 3) int64, faces count)."""
    tris = []
    for f in polys:
        for k in range(1, len(f) - 1):
            tris.append((f[0], f[k], f[k + 1]))
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3), len(polys)


def _load_obj(path):
    verts, polys = [], []
    with open(path, "r", errors="replace") as fh:
        for line in fh:
            if line.startswith("v "):
                s = line.split()
                verts.append((float(s[1]), float(s[2]), float(s[3])))
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/", 1)[0])
                    idx.append(i - 1 if i > 0 else len(verts) + i)
                polys.append(idx)
    return np.asarray(verts, dtype=np.float64).reshape(-1, 3), polys


def _load_off(path):
    with open(path, "r", errors="replace") as fh:
        lines = [l.split("#", 1)[0].split() for l in fh]
    lines = [l for l in lines if l]
    head = lines[0]
    if head[0] != "OFF":
        raise ValueError(f"{path}: not a plain OFF file ({head[0]})")
    counts, at = (head[1:], 1) if len(head) > 1 else (lines[1], 2)
    nv, nf = int(counts[0]), int(counts[1])
    verts = np.asarray([l[:3] for l in lines[at:at + nv]], dtype=np.float64).reshape(nv, 3)
    polys = []
    for l in lines[at + nv:at + nv + nf]:
        n = int(l[0])
        polys.append([int(t) for t in l[1:1 + n]])  # anything after the n indices is a colour
    return verts, polys


_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _load_ply(path):
    with open(path, "rb") as fh:
        data = fh.read()
    end = data.index(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii", "replace").splitlines()
    fmt = None
    elements = []  # [name, count, [(prop, type, list_count_type or None)]]
    for line in header:
        s = line.split()
        if not s:
            continue
        if s[0] == "format":
            fmt = s[1]
        elif s[0] == "element":
            elements.append([s[1], int(s[2]), []])
        elif s[0] == "property":
            if s[1] == "list":
                elements[-1][2].append((s[4], _PLY_TYPES[s[3]], _PLY_TYPES[s[2]]))
            else:
                elements[-1][2].append((s[2], _PLY_TYPES[s[1]], None))
    verts = np.zeros((0, 3))
    polys = []
    body = data[end:]
    if fmt == "ascii":
        lines = body.decode("ascii", "replace").split("\n")
        at = 0
        for name, count, props in elements:
            rows = lines[at:at + count]
            at += count
            if name == "vertex":
                names = [p[0] for p in props]
                cols = [names.index(c) for c in ("x", "y", "z")]
                arr = np.array([r.split() for r in rows], dtype=np.float64)
                verts = arr[:, cols]
            elif name == "face":
                # the vertex index list is the first list property
                for r in rows:
                    t = r.split()
                    k = 0
                    for pname, _, lt in props:
                        if lt is None:
                            k += 1
                            continue
                        n = int(t[k])
                        if pname in ("vertex_indices", "vertex_index"):
                            polys.append([int(x) for x in t[k + 1:k + 1 + n]])
                        k += 1 + n
        return verts, polys
    order = "<" if fmt == "binary_little_endian" else ">"
    at = 0
    for name, count, props in elements:
        if all(p[2] is None for p in props):
            dt = np.dtype([(p[0], order + p[1]) for p in props])
            arr = np.frombuffer(body, dtype=dt, count=count, offset=at)
            at += dt.itemsize * count
            if name == "vertex":
                verts = np.stack([arr[c].astype(np.float64) for c in ("x", "y", "z")], axis=1)
            continue
        # an element with list properties: fast path when it is all triangles (one list, of 3)
        lists = [p for p in props if p[2] is not None]
        if len(lists) == 1 and count > 0:
            fields = []
            for pname, ptype, lt in props:
                if lt is None:
                    fields.append((pname, order + ptype))
                else:
                    fields.append(("_n", order + lt))
                    fields.append((pname, order + ptype, (3,)))
            dt = np.dtype(fields)
            if at + dt.itemsize * count <= len(body):
                arr = np.frombuffer(body, dtype=dt, count=count, offset=at)
                if (arr["_n"] == 3).all():
                    at += dt.itemsize * count
                    if name == "face" and lists[0][0] in ("vertex_indices", "vertex_index"):
                        polys.extend(arr[lists[0][0]].astype(np.int64).tolist())
                    continue
        # otherwise walk it
        for i in range(count):
            for pname, ptype, lt in props:
                if lt is None:
                    at += np.dtype(ptype).itemsize
                    continue
                n = int(np.frombuffer(body, dtype=order + lt, count=1, offset=at)[0])
                at += np.dtype(lt).itemsize
                vals = np.frombuffer(body, dtype=order + ptype, count=n, offset=at)
                at += np.dtype(ptype).itemsize * n
                if name == "face" and pname in ("vertex_indices", "vertex_index"):
                    polys.append(vals.astype(np.int64).tolist())
    return verts, polys


def _load_stl(path):
    with open(path, "rb") as fh:
        data = fh.read()
    if len(data) >= 84:
        n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if 84 + 50 * n == len(data):
            dt = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
            soup = np.frombuffer(data, dtype=dt, count=n, offset=84)["v"].astype(np.float64)
            soup = soup.reshape(-1, 3)
        else:
            n = None
    else:
        n = None
    if n is None:
        vals = [tuple(map(float, l.split()[1:4])) for l in data.decode("ascii", "replace").splitlines()
                if l.strip().startswith("vertex")]
        soup = np.asarray(vals, dtype=np.float64).reshape(-1, 3)
    verts, inv = np.unique(soup, axis=0, return_inverse=True)
    return verts, inv.reshape(-1, 3).tolist()


def load_polygons(path):
    """(vertices (n, 3) float64, faces as lists of indices) of an OBJ / PLY / OFF / STL file."""
    ext = Path(path).suffix.lower()
    loader = {".obj": _load_obj, ".off": _load_off, ".ply": _load_ply, ".stl": _load_stl}[ext]
    return loader(path)


def load_mesh(path):
    """(vertices (n, 3) float64, triangles (m, 3) int64, input face count) of an OBJ / PLY / OFF
    / STL file: positions only, every vertex record kept, polygons fan-triangulated. Positions are
    rounded to float32 first, as every mesh tool here (tessd's readers, Blender, Draco's and
    meshoptimizer's inputs) holds them: quantising the text's float64 values would put a few
    near-tie vertices in the neighbouring grid cell."""
    verts, polys = load_polygons(path)
    verts = np.asarray(verts, dtype=np.float32).astype(np.float64)
    tris, nfaces = _fan(polys)
    return verts, tris, nfaces


def polygon_triangle_check(verts, polys, grid, dec_verts, dec_tris):
    """For inputs with polygons, a check that does not depend on how they are triangulated:
    every decoded triangle (over quantised positions) is a triangle of three corners of one
    input polygon, in the polygon's orientation, and there are as many (distinct,
    non-degenerate) as the input's polygons give (n - 2 each, less the collapsed ones)."""
    from itertools import combinations

    keys = grid.keys(grid.quantize(verts))
    allowed = set()
    for f in polys:
        for i, j, k in combinations(range(len(f)), 3):
            t = (keys[f[i]], keys[f[j]], keys[f[k]])
            if len(set(t)) == 3:
                r = t.index(min(t))
                allowed.add(t[r:] + t[:r])
    dkeys = grid.keys(grid.quantize(dec_verts)) if len(dec_verts) else np.zeros(0, dtype=np.int64)
    dset = triangle_keys(dkeys, np.asarray(dec_tris, dtype=np.int64).reshape(-1, 3))
    fan = triangle_keys(keys, _fan(polys)[0])
    inside = sum(tuple(int(x) for x in t) in allowed for t in dset)
    return {"triangles_in_input_polygons": int(inside), "decoded_unique_triangles": int(len(dset)),
            "input_polygon_triangles": int(len(fan)),
            "triangles_equal_up_to_triangulation": bool(inside == len(dset) == len(fan))}


# ---------------------------------------------------------------------------------------------
# Quantisation and comparisons


class Grid:
    """p bits per coordinate over the cubic bounding box of `verts` (see the module doc)."""

    def __init__(self, verts, bits, origin=None, step=None):
        self.bits = int(bits)
        lo = verts.min(axis=0) if len(verts) else np.zeros(3)
        side = float((verts.max(axis=0) - lo).max()) if len(verts) else 0.0
        self.origin = np.asarray(lo if origin is None else origin, dtype=np.float64)
        self.side = side
        if step is None:
            step = side / ((1 << self.bits) - 1) if side > 0 else 1.0
        self.step = float(step)
        self.top = (1 << self.bits) - 1

    def quantize(self, pts):
        q = np.floor((np.asarray(pts, dtype=np.float64) - self.origin) / self.step + 0.5)
        return np.clip(q, 0, self.top).astype(np.int64)

    def position(self, q):
        return self.origin + np.asarray(q, dtype=np.float64) * self.step

    def keys(self, q):
        """One int64 per grid point (p ≤ 21)."""
        q = np.asarray(q, dtype=np.int64)
        return (q[:, 0] << 42) | (q[:, 1] << 21) | q[:, 2]

    def describe(self):
        return {"origin": self.origin.tolist(), "step": self.step, "bits": self.bits,
                "largest_side": self.side}


def referenced(tris, nverts):
    used = np.zeros(nverts, dtype=bool)
    if tris.size:
        used[tris.reshape(-1)] = True
    return used


def triangle_keys(key_of_vertex, tris):
    """The set (as a sorted unique (k, 3) int64 array) of oriented triangles over vertex keys:
    each rotated to start at its smallest key; triangles with two equal keys dropped."""
    if tris.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    t = key_of_vertex[tris]
    ok = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    t = t[ok]
    r = np.argmin(t, axis=1)
    rows = np.arange(len(t))
    t = np.stack([t[rows, r], t[rows, (r + 1) % 3], t[rows, (r + 2) % 3]], axis=1)
    return np.unique(t, axis=0)


def quantised_summary(verts, tris, grid):
    """Counts the quantised input: unique grid points (all vertices / referenced ones) and
    unique oriented non-degenerate triangles; also returns the sets for the lossless checks."""
    keys = grid.keys(grid.quantize(verts))
    used = referenced(tris, len(verts))
    all_set = np.unique(keys)
    ref_set = np.unique(keys[used])
    tri_set = triangle_keys(keys, tris)
    return {
        "unique_quantised_vertices": int(all_set.size),
        "unique_quantised_referenced": int(ref_set.size),
        "unique_quantised_triangles": int(len(tri_set)),
    }, {"all": all_set, "ref": ref_set, "tris": tri_set}


# A decoded position may sit this far (in grid steps) from its grid point and still count as on
# it: a float32 PLY at p = 16 is off by ~0.003 steps on the bunny.
OFFGRID_TOL = 0.1


def lossless_check(sets, dec_verts, dec_tris, grid):
    """Compares a decoded mesh with the quantised input sets (see the module doc)."""
    keys = grid.keys(grid.quantize(dec_verts)) if len(dec_verts) else np.zeros(0, dtype=np.int64)
    dset = np.unique(keys)
    # decoded positions must sit on grid points (else they were not decoded at precision p)
    if len(dec_verts):
        off = np.abs(np.asarray(dec_verts, np.float64) - grid.position(grid.quantize(dec_verts)))
        off_grid = float(off.max() / grid.step)
    else:
        off_grid = 0.0
    tset = triangle_keys(keys, np.asarray(dec_tris, dtype=np.int64).reshape(-1, 3))
    pos_ref = bool(np.array_equal(dset, sets["ref"]))
    pos_all = bool(np.array_equal(dset, sets["all"]))
    tri_eq = bool(np.array_equal(tset, sets["tris"]))
    return {
        "positions_equal_referenced": pos_ref,
        "positions_equal_all": pos_all,
        "triangles_equal": tri_eq,
        "lossless": (pos_ref or pos_all) and tri_eq and off_grid < OFFGRID_TOL,
        "decoded_unique_positions": int(dset.size),
        "decoded_unique_triangles": int(len(tset)),
        "max_offgrid_steps": off_grid,
        "positions_missing": int(np.setdiff1d(sets["ref"], dset).size),
        "positions_extra": int(np.setdiff1d(dset, sets["all"]).size),
    }


def vertex_error(verts, tris, dec_verts, grid):
    """Max / RMS distance of each referenced input vertex to its decoded vertex (same grid key,
    else the nearest decoded vertex)."""
    from scipy.spatial import cKDTree

    used = referenced(tris, len(verts))
    v = verts[used]
    if len(dec_verts) == 0 or len(v) == 0:
        return {"max_err": float("nan"), "rms_err": float("nan")}
    dec = np.asarray(dec_verts, dtype=np.float64)
    dkeys = grid.keys(grid.quantize(dec))
    order = np.argsort(dkeys, kind="stable")
    skeys = dkeys[order]
    vkeys = grid.keys(grid.quantize(v))
    at = np.clip(np.searchsorted(skeys, vkeys), 0, len(skeys) - 1)
    hit = skeys[at] == vkeys
    d = np.empty(len(v))
    d[hit] = np.linalg.norm(v[hit] - dec[order[at[hit]]], axis=1)
    if (~hit).any():
        d[~hit] = cKDTree(dec).query(v[~hit])[0]
    side = grid.side if grid.side > 0 else 1.0
    return {
        "max_err": float(d.max()), "rms_err": float(np.sqrt(np.mean(d * d))),
        "max_err_rel": float(d.max() / side), "rms_err_rel": float(np.sqrt(np.mean(d * d)) / side),
        "err_unmatched_vertices": int((~hit).sum()),
    }


# ---------------------------------------------------------------------------------------------
# Surface distances (rate-distortion)


def sample_surface(verts, tris, n, seed=0):
    """Area-weighted uniform samples on the triangles, plus every referenced vertex."""
    rng = np.random.default_rng(seed)
    used = referenced(tris, len(verts))
    pts = [verts[used] if tris.size else verts]
    if tris.size and n > 0:
        a, b, c = (verts[tris[:, k]] for k in range(3))
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        if area.sum() > 0:
            i = rng.choice(len(tris), size=n, p=area / area.sum())
            r1, r2 = rng.random(n), rng.random(n)
            s = np.sqrt(r1)
            u, w = 1 - s, s * r2
            pts.append(a[i] * u[:, None] + b[i] * (s * (1 - r2))[:, None] + c[i] * w[:, None])
    return np.concatenate(pts, axis=0)


def closest_point_on_triangles(tri, p):
    """Closest point of each triangle tri[i] (n, 3, 3) to p[i] (n, 3): Ericson's Voronoi-region
    test (Real-Time Collision Detection, 5.1.5), vectorised, no tolerances (trimesh's version
    snaps with an absolute tolerance and is wrong on sub-millimetre triangles)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)  # noqa: E731
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        out = a + ab * (vb / denom)[:, None] + ac * (vc / denom)[:, None]  # inside the face
        done = np.zeros(len(p), dtype=bool)

        def put(mask, value):
            m = mask & ~done
            out[m] = value[m]
            done[m] = True

        put((d1 <= 0) & (d2 <= 0), a)
        put((d3 >= 0) & (d4 <= d3), b)
        put((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * (d1 / (d1 - d3))[:, None])
        put((d6 >= 0) & (d5 <= d6), c)
        put((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * (d2 / (d2 - d6))[:, None])
        put((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),
            b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None])
    return out


def point_mesh_distance(points, verts, tris, chunk=20000):
    """Exact distance from each point to the union of the triangles (point-triangle closest
    points, closest_point_on_triangles), the candidates pruned with KD-trees over triangle
    centroids binned by circumradius; to the vertices alone when there is no non-degenerate
    triangle."""
    from scipy.spatial import cKDTree

    closest_point = closest_point_on_triangles
    points = np.asarray(points, dtype=np.float64)
    tri = verts[tris] if tris.size else np.zeros((0, 3, 3))
    if len(tri):
        area2 = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        tri = tri[area2 > 0]
    if len(tri) == 0:
        src = verts[referenced(tris, len(verts))] if tris.size else verts
        return cKDTree(src).query(points)[0]
    cen = tri.mean(axis=1)
    rad = np.linalg.norm(tri - cen[:, None, :], axis=2).max(axis=1)
    # bins of radii within a factor 2 of each other
    lo = max(rad.max(), 1e-300) * 2.0 ** -30
    b = np.floor(np.log2(np.maximum(rad, lo) / lo)).astype(int)
    bins = []
    for k in np.unique(b):
        idx = np.nonzero(b == k)[0]
        bins.append((idx, cKDTree(cen[idx]), float(rad[idx].max())))
    gtree = cKDTree(cen)
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk]
        kk = min(4, len(tri))
        _, near = gtree.query(p, k=kk)
        near = near.reshape(len(p), kk)
        rows = np.repeat(np.arange(len(p)), kk)
        cp = closest_point(tri[near.reshape(-1)], p[rows])
        best = np.linalg.norm(cp - p[rows], axis=1).reshape(len(p), kk).min(axis=1)
        for idx, tree, rmax in bins:
            cand = tree.query_ball_point(p, best + rmax * (1 + 1e-9) + 1e-12)
            lens = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
            if lens.sum() == 0:
                continue
            prow = np.repeat(np.arange(len(p)), lens)
            tix = idx[np.concatenate([np.asarray(c, dtype=np.int64) for c in cand if len(c)])]
            for t0 in range(0, len(prow), 400000):
                pr, tx = prow[t0:t0 + 400000], tix[t0:t0 + 400000]
                d = np.linalg.norm(closest_point(tri[tx], p[pr]) - p[pr], axis=1)
                np.minimum.at(best, pr, d)
        out[s:s + len(p)] = best
    return out


def surface_distance(ref_v, ref_t, dec_v, dec_t, samples=100000, seed=0):
    """Symmetric sampled point-to-surface distances (see point_mesh_distance): forward = samples
    of the reference to the decoded surface, backward = samples of the decoded to the reference;
    hausdorff = the larger max, rms over both sample sets."""
    a = sample_surface(ref_v, ref_t, samples, seed)
    b = sample_surface(dec_v, dec_t, samples, seed + 1)
    fwd = point_mesh_distance(a, dec_v, dec_t)
    bwd = point_mesh_distance(b, ref_v, ref_t)
    both = np.concatenate([fwd, bwd])
    return {
        "hausdorff": float(both.max()), "rms": float(np.sqrt(np.mean(both * both))),
        "max_fwd": float(fwd.max()), "rms_fwd": float(np.sqrt(np.mean(fwd * fwd))),
        "max_bwd": float(bwd.max()), "rms_bwd": float(np.sqrt(np.mean(bwd * bwd))),
        "samples_fwd": int(len(a)), "samples_bwd": int(len(b)),
        "decoded_has_surface": bool(dec_t.size > 0),
    }


# ---------------------------------------------------------------------------------------------
# Timing


def _status_kib(key):
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    return 0


def peak_of(fn):
    """(result, peak resident growth in KiB) of one call of fn: the heap trimmed and the
    kernel's peak (VmHWM) reset through /proc/self/clear_refs first; None where that fails."""
    import ctypes
    import gc

    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except OSError:
        pass
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        ok = True
    except OSError:
        ok = False
    before = _status_kib("VmRSS")
    res = fn()
    peak = _status_kib("VmHWM")
    return res, (peak - before if ok else None)


def timed(fn, budget=1.0, min_repeat=3, max_repeat=25):
    """(last result, median seconds, repeats) of fn() repeated until `budget` seconds."""
    times = []
    t_all = time.perf_counter()
    res = None
    while len(times) < max_repeat:
        t = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t)
        if len(times) >= min_repeat and time.perf_counter() - t_all >= budget:
            break
    return res, statistics.median(times), len(times)


# ---------------------------------------------------------------------------------------------
# Peers


def draco_rows(verts, tris, grid, sets, level, budget):
    import DracoPy

    # Draco gets the grid integers themselves (exact in float32 for p <= 24) over the range
    # 2^p - 1 from origin 0, so that its quantiser maps each onto itself: the same quantised mesh
    # as tessd's, bit for bit (given the float positions, its float32 arithmetic puts a few
    # near-tie vertices in the neighbouring cell: 8 of the bunny's at p = 12). The bitstream is
    # the one it would write for the float mesh but for those ties and the header's origin/range.
    pts = np.ascontiguousarray(grid.quantize(verts), dtype=np.float32)
    faces = np.ascontiguousarray(tris, dtype=np.uint32)
    kw = dict(quantization_bits=grid.bits, compression_level=level,
              quantization_range=float(grid.top), quantization_origin=[0.0, 0.0, 0.0])
    buf, mem_enc = peak_of(lambda: DracoPy.encode(pts, faces, **kw))
    _, mem_dec = peak_of(lambda: DracoPy.decode(buf))
    buf, t_enc, n_enc = timed(lambda: DracoPy.encode(pts, faces, **kw), budget)
    dec, t_dec, n_dec = timed(lambda: DracoPy.decode(buf), budget)
    # for the record: the size it writes from the float positions (its own quantisation)
    float_bytes = len(DracoPy.encode(
        np.ascontiguousarray(verts, dtype=np.float32), faces, quantization_bits=grid.bits,
        compression_level=level, quantization_range=float(grid.side) if grid.side > 0 else -1,
        quantization_origin=[float(x) for x in grid.origin]))
    dv = grid.position(np.asarray(dec.points, dtype=np.float64).reshape(-1, 3))
    dt = np.asarray(dec.faces, dtype=np.int64).reshape(-1, 3)
    row = {
        "tool": "draco", "variant": f"draco-{level}", "compression_level": level,
        "bytes": len(buf), "bytes_from_float_input": float_bytes, "encode_ms": 1e3 * t_enc, "decode_ms": 1e3 * t_dec,
        "encode_repeats": n_enc, "decode_repeats": n_dec,
        "encode_peak_kib": mem_enc, "decode_peak_kib": mem_dec,
        "decoded_vertices": int(len(dv)), "decoded_triangles": int(len(dt)),
        "library": f"DracoPy {_version('DracoPy')}",
    }
    row.update(lossless_check(sets, dv, dt, grid))
    row.update(vertex_error(verts, tris, dv, grid))
    return [row]


def meshopt_rows(verts, tris, grid, sets, budget):
    import meshopt
    import zstandard

    # 4 x uint16 rows (8 bytes) up to p = 16, else 3 x uint32 (12 bytes)
    q = grid.quantize(verts)
    if grid.bits <= 16:
        q4 = np.zeros((len(q), 4), dtype=np.uint16)
        q4[:, :3] = q
    else:
        q4 = np.ascontiguousarray(q, dtype=np.uint32)
    row_bytes = q4.itemsize * q4.shape[1]
    idx = np.ascontiguousarray(tris.reshape(-1), dtype=np.uint32)

    def prep():
        new_idx, remap, unique = meshopt.reorder_mesh(idx, triangles=True, optsize=False)
        out = np.zeros((unique, q4.shape[1]), dtype=q4.dtype)
        used = remap != 0xFFFFFFFF
        out[remap[used]] = q4[used]
        return new_idx, out

    (new_idx, vbuf), t_prep, n_prep = timed(prep, budget)
    nv = len(vbuf)
    nidx = len(new_idx)
    ib, t_ienc, _ = timed(lambda: meshopt.encode_index_buffer(new_idx), budget)
    idec, t_idec, _ = timed(lambda: meshopt.decode_index_buffer(ib, nidx, 4), budget)
    rows = []
    # (vertex codec version, level, variant suffix): v1 level 3 is the table's "meshopt"
    for version, level, suffix in ((1, 3, ""), (1, 2, "-v1l2"), (0, 2, "-v0")):
        zc = zstandard.ZstdCompressor(level=19)
        zd = zstandard.ZstdDecompressor()

        def enc_all():
            new_idx2, vbuf2 = prep()
            vb2 = meshopt.encode_vertex_buffer_level(vbuf2, level, version)
            ib2 = meshopt.encode_index_buffer(new_idx2)
            return vb2 + ib2, zc.compress(vb2 + ib2)

        (raw, z), mem_enc = peak_of(enc_all)

        def dec_all():
            r = zd.decompress(z)
            return (meshopt.decode_vertex_buffer(r[:len(raw) - len(ib)], nv, row_bytes),
                    meshopt.decode_index_buffer(r[len(raw) - len(ib):], nidx, 4))

        _, mem_dec = peak_of(dec_all)
        vb, t_venc, n_venc = timed(
            lambda: meshopt.encode_vertex_buffer_level(vbuf, level, version), budget)
        vdec, t_vdec, n_vdec = timed(lambda: meshopt.decode_vertex_buffer(vb, nv, row_bytes), budget)
        dv = grid.position(vdec.view(q4.dtype).reshape(nv, q4.shape[1])[:, :3])
        dt = np.asarray(idec, dtype=np.int64).reshape(-1, 3)
        raw = vb + ib
        z, t_z, _ = timed(lambda: zc.compress(raw), budget)
        _, t_uz, _ = timed(lambda: zd.decompress(z), budget)
        d, t_d, _ = timed(lambda: zlib.compress(raw, 9), budget)
        _, t_ud, _ = timed(lambda: zlib.decompress(d), budget)
        base = {
            "tool": "meshopt", "vertex_codec_version": version, "vertex_codec_level": level,
            "prepare_ms": 1e3 * t_prep, "decoded_vertices": nv, "decoded_triangles": nidx // 3,
            "vertex_bytes": len(vb), "index_bytes": len(ib),
            # peak resident growth of one whole encode (reorder + both codecs + zstd) / decode
            "encode_peak_kib": mem_enc, "decode_peak_kib": mem_dec,
            "library": f"meshopt {_version('meshopt')} (meshoptimizer 1.3), zstandard {_version('zstandard')}",
        }
        base.update(lossless_check(sets, dv, dt, grid))
        base.update(vertex_error(verts, tris, dv, grid))
        enc = t_venc + t_ienc
        dec = t_vdec + t_idec
        rows.append(dict(base, variant="meshopt" + suffix, bytes=len(raw),
                         encode_ms=1e3 * enc, decode_ms=1e3 * dec))
        rows.append(dict(base, variant="meshopt+zstd" + suffix, bytes=len(z), compressor="zstd -19",
                         encode_ms=1e3 * (enc + t_z), decode_ms=1e3 * (dec + t_uz)))
        rows.append(dict(base, variant="meshopt+deflate" + suffix, bytes=len(d), compressor="zlib -9",
                         encode_ms=1e3 * (enc + t_d), decode_ms=1e3 * (dec + t_ud)))
    return rows


def _version(dist):
    try:
        from importlib.metadata import version
        return version(dist)
    except Exception:
        return "?"


def mesh_info(path, verts, tris, nfaces, grid):
    summary, sets = quantised_summary(verts, tris, grid)
    info = {
        "mesh": Path(path).stem, "path": str(path), "p": grid.bits,
        "input_vertices": int(len(verts)), "input_faces": int(nfaces),
        "input_triangles": int(len(tris)),
        "referenced_vertices": int(referenced(tris, len(verts)).sum()),
        "grid": grid.describe(),
    }
    info.update(summary)
    return info, sets


def one(path, bits, peer, budget):
    """Child: one peer on one mesh at p bits; returns the rows."""
    import scipy.spatial  # noqa: F401 — imported before the memory baselines
    if peer.startswith("draco"):
        import DracoPy  # noqa: F401
    elif peer == "meshopt":
        import meshopt  # noqa: F401
        import zstandard  # noqa: F401
    t = time.perf_counter()
    verts, tris, nfaces = load_mesh(path)
    t_load = time.perf_counter() - t
    grid = Grid(verts, bits)
    info, sets = mesh_info(path, verts, tris, nfaces, grid)
    info["load_ms"] = 1e3 * t_load
    if peer == "load":
        rows = [{"tool": "load", "variant": "load"}]
    elif peer.startswith("draco-"):
        rows = draco_rows(verts, tris, grid, sets, int(peer.split("-")[1]), budget)
    elif peer == "meshopt":
        rows = meshopt_rows(verts, tris, grid, sets, budget)
    else:
        raise SystemExit(f"unknown peer {peer}")
    out = []
    for r in rows:
        row = dict(info)
        row.update(r)
        if "bytes" in row:
            row["bits_per_vertex"] = 8.0 * row["bytes"] / max(1, row["input_vertices"])
            row["bits_per_referenced_vertex"] = 8.0 * row["bytes"] / max(1, row["referenced_vertices"])
        out.append(row)
    return out


GNU_TIME = "/usr/bin/time"


def run_child_rss(argv, timeout=None):
    """Runs a command: (returncode or None on timeout, stdout, stderr, its own peak RSS in KiB,
    wall seconds). The peak comes from GNU time (`/usr/bin/time -f %M`, Debian package `time`),
    which forks the command from its own small process: the ru_maxrss that wait4 gives for a
    child of this (large) Python process would start at this process's size, which the kernel
    carries across exec. Without GNU time: the child's VmHWM polled every millisecond (may miss
    a peak in its last millisecond)."""
    import tempfile

    use_time = os.access(GNU_TIME, os.X_OK)
    t = time.perf_counter()
    with tempfile.TemporaryFile("w+") as fo, tempfile.TemporaryFile("w+") as fe, \
            tempfile.NamedTemporaryFile("w+", suffix=".rss") as fr:
        cmd = [GNU_TIME, "-q", "-o", fr.name, "-f", "%M"] + list(argv) if use_time else list(argv)
        proc = subprocess.Popen(cmd, stdout=fo, stderr=fe, text=True)
        deadline = None if timeout is None else time.monotonic() + timeout
        hwm = 0
        while True:
            pid, status, _ = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if not use_time:
                try:
                    with open(f"/proc/{proc.pid}/status") as fh:
                        for line in fh:
                            if line.startswith("VmHWM:"):
                                hwm = max(hwm, int(line.split()[1]))
                except (OSError, ValueError):
                    pass
            if deadline is not None and time.monotonic() > deadline:
                proc.kill()
                os.wait4(proc.pid, 0)
                status = None
                break
            time.sleep(0.001)
        proc.returncode = os.waitstatus_to_exitcode(status) if status is not None else None
        wall = time.perf_counter() - t
        fo.seek(0)
        fe.seek(0)
        rss = hwm or None
        if use_time:
            fr.seek(0)
            lines = [l for l in fr.read().split() if l.strip().isdigit()]
            rss = int(lines[-1]) if lines else None
        return proc.returncode, fo.read(), fe.read(), rss, wall


PEERS = ("load", "draco-10", "draco-7", "meshopt")


def peer_rows(path, bits, peers=PEERS, budget=1.0, timeout=600):
    """All peers' rows for one mesh at p bits, each from its own child; the `load` child's
    peak RSS is the baseline (`peak_rss_delta_kib`)."""
    rows = []
    base = None
    for peer in peers:
        argv = [sys.executable, str(HERE / "peers.py"), "one", "--mesh", str(path), "--bits", str(bits),
                "--peer", peer, "--budget", str(budget)]
        rc, out, err, rss, wall = run_child_rss(argv, timeout)
        if rc != 0:
            rows.append({"mesh": Path(path).stem, "path": str(path), "p": bits, "tool": peer.split("-")[0],
                         "variant": peer, "error": (err or "").strip()[-2000:] or f"exit {rc}"})
            continue
        got = json.loads(out)
        for r in got:
            r["peak_rss_kib"] = rss
            r["child_wall_s"] = wall
        if peer == "load":
            base = rss
            continue
        for r in got:
            r["baseline_rss_kib"] = base
            if base is not None and rss is not None:
                r["peak_rss_delta_kib"] = rss - base
        rows.extend(got)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    o = sub.add_parser("one")
    o.add_argument("--mesh", required=True)
    o.add_argument("--bits", type=int, required=True)
    o.add_argument("--peer", required=True, choices=PEERS)
    o.add_argument("--budget", type=float, default=1.0)
    r = sub.add_parser("run")
    r.add_argument("--mesh", required=True, help="comma-separated paths")
    r.add_argument("--bits", default="12,16")
    r.add_argument("--peers", default=",".join(PEERS[1:]))
    r.add_argument("--budget", type=float, default=1.0)
    r.add_argument("--jsonl")
    a = ap.parse_args()
    if a.cmd == "one":
        json.dump(one(a.mesh, a.bits, a.peer, a.budget), sys.stdout)
        return
    peers = ["load"] + [p for p in a.peers.split(",") if p and p != "load"]
    for path in a.mesh.split(","):
        for bits in (int(b) for b in a.bits.split(",")):
            for row in peer_rows(path, bits, peers, a.budget):
                line = json.dumps(row)
                if a.jsonl:
                    with open(a.jsonl, "a") as fh:
                        fh.write(line + "\n")
                if "error" in row:
                    print(f"{row['mesh']} p={bits} {row['variant']}: ERROR {row['error'][-300:]}", file=sys.stderr)
                elif "skipped" in row:
                    print(f"{row['mesh']} p={bits} {row['variant']}: skipped ({row['skipped']})")
                else:
                    print(f"{row['mesh']} p={bits} {row['variant']}: {row['bytes']} B, "
                          f"{row['bits_per_vertex']:.2f} b/v, enc {row['encode_ms']:.2f} ms, "
                          f"dec {row['decode_ms']:.2f} ms, lossless {row['lossless']}, "
                          f"max err {row.get('max_err_rel', float('nan')):.2e} side, "
                          f"rss +{row.get('peak_rss_delta_kib')} KiB")


if __name__ == "__main__":
    main()
