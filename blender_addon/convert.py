"""Blender meshes <-> the protocol's mesh arrays (docs/protocol.md, "Mesh arrays").

Everything goes through `foreach_get` / `foreach_set` of the mesh's attributes into numpy
arrays of the attribute's own dtype (:func:`read`, :func:`write`: one copy, no per-element
conversion), never a Python loop over vertices, faces or corners (vertex group weights are the
one exception: Blender has no bulk access to them), so a million-triangle mesh converts in a
few milliseconds.

Mapping:
- positions: vertex `co` (object space; the object's transform stays on the object);
- faces: corner vertex indices in face order (`face_indices`), [F, 3] when every face is a
  triangle, else 1-D with the corner counts (`face_sizes`);
- UVs: the active UV map as `uvs`, one UV per corner; the other UV maps, colour attributes
  and every other point / corner / face attribute, vertex groups, shape keys and sharp edges
  as the protocol's attribute arrays (attributes.py);
- normals: only when custom normals are asked for (shading.py): by default a result gets
  Blender's own normals from the carried `sharp_face` / `sharp_edge`;
- creases: the float edge attribute `crease_edge` (Blender 4+) as OpenSubdiv sharpness
  10·c² (Blender's own `crease_to_sharpness`), and back as c = sqrt(s / 10);
- materials: `material_index` as `face_groups`, the material slots' names as `group_names`;
  a result gets the source's materials in the same slots."""

import contextlib

import bpy
import numpy as np

from . import attributes as attrs
from . import shading

SHARPNESS_INFINITE = 10.0


@contextlib.contextmanager
def source_mesh(obj, depsgraph, evaluated):
    """The mesh to send for `obj`: with its modifiers applied (evaluated) or its own data."""
    if not evaluated:
        yield obj.data
        return
    obj_eval = obj.evaluated_get(depsgraph)
    mesh = obj_eval.to_mesh()
    try:
        yield mesh
    finally:
        obj_eval.to_mesh_clear()


def read(mesh, name, key, dtype, rows, comps=1, fallback=None):
    """The attribute `name` of `mesh` read by `foreach_get(key)` straight into a new numpy
    array of `dtype` and shape [rows] or [rows, comps], or None when the mesh lacks it.

    `dtype` must be the attribute's own type (f32 for floats, i32 / i8 / i16 for integers,
    bool): Blender then copies the whole array in one go (about 1 ms for a million vertices);
    another dtype converts element by element through Python's RNA layer (about 100 ms).
    `fallback` (a collection and its key, e.g. ``(mesh.loops, "vertex_index")``) is read the
    same way when the attribute is not exposed (an internal attribute of another version)."""
    out = np.empty(rows * comps, dtype=dtype)
    attr = mesh.attributes.get(name)
    if attr is not None:
        attr.data.foreach_get(key, out)
    elif fallback is not None:
        fallback[0].foreach_get(fallback[1], out)
    else:
        return None
    return out.reshape(rows, comps) if comps > 1 else out


def write(mesh, name, key, values, fallback=None):
    """Writes `values` (of the attribute's own dtype, see :func:`read`) into the existing
    attribute `name` of `mesh`, or into `fallback` (a collection and its key) when the
    attribute is not exposed."""
    values = np.ascontiguousarray(values).reshape(-1)
    attr = mesh.attributes.get(name)
    if attr is not None:
        attr.data.foreach_set(key, values)
    else:
        fallback[0].foreach_set(fallback[1], values)


def positions_of(mesh):
    return read(mesh, "position", "vector", np.float32, len(mesh.vertices), 3,
                fallback=(mesh.vertices, "co"))


def corner_vertices(mesh):
    """The vertex of every face corner, in face order (u32). Since Blender 4.0 a mesh stores
    its faces as offsets into the corner arrays, so the corners are in face order by
    construction (a face's corners are offsets[f]..offsets[f + 1])."""
    out = read(mesh, ".corner_vert", "value", np.int32, len(mesh.loops),
               fallback=(mesh.loops, "vertex_index"))
    return out.view(np.uint32)


def face_sizes_of(mesh):
    """The corner count of every face (u32), or None when every face is a triangle: a face
    has at least 3 corners, so 3 × faces corners means only triangles (nothing to read)."""
    n_f, n_l = len(mesh.polygons), len(mesh.loops)
    if n_l == 3 * n_f:
        return None
    starts = np.empty(n_f, dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    sizes = np.empty(n_f, dtype=np.uint32)
    if n_f:
        np.subtract(starts[1:], starts[:-1], out=sizes[:-1], casting="unsafe")
        sizes[-1] = n_l - starts[-1]
    return sizes


def face_count(arrays, prefix=""):
    """Faces of protocol arrays: 1-D `face_indices` with `face_sizes`, or [F, n]."""
    sizes = arrays.get(prefix + "face_sizes")
    return len(sizes) if sizes is not None else len(arrays[prefix + "face_indices"])


def triangle_count(arrays):
    """Triangles of protocol arrays once every polygon is split into a fan."""
    sizes = arrays.get("face_sizes")
    if sizes is not None:
        return int((sizes.astype(np.int64) - 2).sum())
    fi = arrays["face_indices"]
    return len(fi) * (fi.shape[1] - 2)


def group_names_of(obj):
    """Names of the object's material slots, unique (the daemon's face group names)."""
    names, seen = [], set()
    for i, slot in enumerate(obj.material_slots):
        base = slot.material.name if slot.material else "slot%d" % i
        name, k = base, 1
        while name in seen:
            k += 1
            name = "%s.%d" % (base, k)
        seen.add(name)
        names.append(name)
    return names


def mesh_to_arrays(mesh, obj=None, *, normals=False, uvs=True, creases=True, attributes=True,
                   shape_keys=False, uniform_sharp_face=True):
    """The protocol arrays of `mesh`, the params they need (`group_names`) and what was sent
    besides the geometry (an :class:`attributes.Sent`, for rebuilding the results).

    `obj` gives the material slots (face groups are sent only when it has any) and the
    vertex groups; `normals` sends Blender's corner normals (to be carried as custom
    normals); `shape_keys` sends the mesh's shape keys (only meaningful for the object's own
    mesh, not an evaluated one); `uniform_sharp_face` false leaves out a `sharp_face` that is
    the same on every face (for results that only come back to Blender: attributes.collect)."""
    if len(mesh.polygons) == 0:
        raise ValueError("it has no faces")
    # Each array is read once, straight into its final dtype (convert.read); what the mesh
    # does not have is not sent. A mesh of triangles sends `face_indices` [F, 3] and no
    # `face_sizes`.
    n_l, n_f = len(mesh.loops), len(mesh.polygons)
    corner_verts = corner_vertices(mesh)
    sizes = face_sizes_of(mesh)
    arrays = {"positions": positions_of(mesh)}
    if sizes is None:
        arrays["face_indices"] = corner_verts.reshape(n_f, 3)
    else:
        arrays["face_indices"] = corner_verts
        arrays["face_sizes"] = sizes
    params = {}
    sent = attrs.Sent()
    layer = mesh.uv_layers.active if uvs else None
    if layer is not None:
        # The active UV map travels as `uvs` (USD writes it as `st`); the others as
        # generic corner attributes.
        arrays["uvs"] = read(mesh, layer.name, "vector", np.float32, n_l, 2,
                             fallback=(layer.data, "uv"))
        sent.uv_name = layer.name
    if normals:
        nrm = np.empty(n_l * 3, dtype=np.float32)
        mesh.corner_normals.foreach_get("vector", nrm)
        arrays["normals"] = nrm.reshape(-1, 3)
    elif mesh.has_custom_normals:
        sent.dropped.append("custom normals (Blender's normals are used; choose Normals: "
                            "Custom to carry them)")
    if creases and len(mesh.edges):
        attr = mesh.attributes.get("crease_edge")
        values = (read(mesh, "crease_edge", "value", np.float32, len(mesh.edges))
                  if attr is not None and attr.domain == 'EDGE' else None)
        keep = values > 0.0 if values is not None else None
        if keep is not None and keep.any():
            c = np.minimum(values[keep], np.float32(1.0))
            arrays["crease_edges"] = attrs.edge_vertices(mesh)[keep]
            arrays["crease_values"] = c * c * np.float32(SHARPNESS_INFINITE)
    if attributes:
        attrs.collect(mesh, obj, arrays, sent, skip={sent.uv_name} if sent.uv_name else (),
                      uniform_sharp_face=uniform_sharp_face)
        if shape_keys:
            attrs.collect_shape_keys(mesh, arrays, sent)
    if obj is not None and len(obj.material_slots) > 0:
        # No `material_index` attribute: every face uses the first slot.
        mat = read(mesh, "material_index", "value", np.int32, n_f)
        last = len(obj.material_slots) - 1
        arrays["face_groups"] = (np.zeros(n_f, dtype=np.uint32) if mat is None
                                 else np.clip(mat, 0, last).view(np.uint32))
        params["group_names"] = group_names_of(obj)
    return arrays, params, sent


def _get(arrays, name, prefix):
    return arrays.get(prefix + name)


def _per_corner(values, indices):
    """One row of `values` per corner: `values[indices]` (as they are without indices)."""
    if values is None:
        return None
    values = np.asarray(values)
    if indices is None:
        return values
    indices = np.asarray(indices)
    if values.ndim == 2 and values.shape[1] == 2 and values.dtype == np.float32:
        # A UV pair is 8 bytes: gathered as one u64 per corner, several times faster than rows.
        pairs = np.ascontiguousarray(values).view(np.uint64).reshape(-1)
        return np.take(pairs, indices).view(np.float32).reshape(-1, 2)
    return np.take(values, indices, axis=0)


def drop_loose(arrays, frames=None):
    """`arrays` (and animation `frames` [F, V, 3]) without the vertices no face uses.

    Subdivision has no rule for a loose vertex and the daemon refuses one; Blender meshes often
    carry a few (leftovers of edits), so they are left out of what is sent. Point attributes,
    creases and sharp edges on loose vertices go with them."""
    used = np.zeros(len(arrays["positions"]), dtype=bool)
    used[arrays["face_indices"]] = True
    if used.all():
        return arrays, frames
    remap = np.cumsum(used, dtype=np.int64) - 1
    out = dict(arrays, positions=arrays["positions"][used],
               face_indices=remap[arrays["face_indices"]].astype(np.uint32))
    for name in [k for k in arrays if k.startswith("point:")]:
        out[name] = np.ascontiguousarray(arrays[name][used])
    for edges, values in (("crease_edges", "crease_values"), ("sharp_edges", None)):
        if edges not in arrays:
            continue
        keep = used[arrays[edges]].all(axis=1)
        out[edges] = remap[arrays[edges][keep]].astype(np.uint32)
        if values:
            out[values] = arrays[values][keep]
        if not keep.any():
            out.pop(edges)
            out.pop(values, None)
    return out, (None if frames is None else np.ascontiguousarray(frames[:, used]))


def mesh_from_arrays(name, arrays, *, materials=(), uv_name="UVMap", prefix="", sent=None,
                     shading_mode='BLENDER'):
    """A new mesh from a reply's arrays (`prefix` e.g. "lod1." for the `lod` op).

    `materials` fill the slots in order, so face group i gets material slot i. With `sent`
    (what the input sent), its generic attributes are restored and the names the reply
    lacks are added to `sent.missing`. `shading_mode`: 'BLENDER' (Blender's normals from the
    carried sharp faces and edges) or 'CUSTOM' (the reply's `normals` as custom normals);
    either way no corner normal is left facing away from its face (shading.py)."""
    # Each array is written once in the attribute's own dtype (convert.write), then one
    # `mesh.update(calc_edges=True)` builds the edges.
    pos = np.ascontiguousarray(_get(arrays, "positions", prefix), dtype=np.float32).reshape(-1, 3)
    fi = np.asarray(_get(arrays, "face_indices", prefix))
    fs = _get(arrays, "face_sizes", prefix)
    if fs is None:  # [F, n] faces
        n = fi.shape[-1]
        n_f = fi.size // n
        starts = np.arange(0, n * n_f, n, dtype=np.int32)
    else:
        n_f = len(fs)
        starts = np.zeros(n_f, dtype=np.int32)
        if n_f:
            np.cumsum(np.asarray(fs[:-1], dtype=np.int32), out=starts[1:])
    fi = np.ascontiguousarray(fi.reshape(-1), dtype=np.int32)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(pos))
    write(mesh, "position", "vector", pos, fallback=(mesh.vertices, "co"))
    mesh.loops.add(len(fi))
    write(mesh, ".corner_vert", "value", fi, fallback=(mesh.loops, "vertex_index"))
    mesh.polygons.add(n_f)
    # Faces are offsets into the corners (Blender 4+): a face's size is the distance to the
    # next face's start, so the starts alone define them.
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.update(calc_edges=True)

    for mat in materials:
        mesh.materials.append(mat)
    groups = _get(arrays, "face_groups", prefix)
    if groups is not None and len(materials) > 1:
        idx = np.clip(np.asarray(groups, dtype=np.int32), 0, len(materials) - 1)
        if idx.any():
            attr = mesh.attributes.get("material_index") or mesh.attributes.new(
                "material_index", 'INT', 'FACE')
            attr.data.foreach_set("value", np.ascontiguousarray(idx))

    uvs = _per_corner(_get(arrays, "uvs", prefix), _get(arrays, "uv_indices", prefix))
    uv_name = sent.uv_name if sent is not None and sent.uv_name else uv_name
    if uvs is not None and len(uvs) == len(fi):
        layer = mesh.uv_layers.new(name=uv_name, do_init=False)
        write(mesh, layer.name, "vector", np.asarray(uvs, dtype=np.float32),
              fallback=(layer.data, "uv"))
    elif sent is not None and sent.uv_name:
        sent.missing.add("UV map " + sent.uv_name)
    if sent is not None:
        sent.missing.update(attrs.apply_generic(mesh, arrays, prefix, sent))
        if sent.all_sharp_faces:
            shading.set_sharp_faces(mesh, np.ones(len(mesh.polygons), dtype=bool), update=False)

    crease_edges = _get(arrays, "crease_edges", prefix)
    if crease_edges is not None and len(crease_edges):
        set_creases(mesh, np.asarray(crease_edges), np.asarray(_get(arrays, "crease_values", prefix)))
    sharp = _get(arrays, "sharp_edges", prefix)
    if sharp is not None and len(sharp):
        attrs.set_edge_flags(mesh, sharp)
    mesh.update()

    normals = _per_corner(_get(arrays, "normals", prefix), _get(arrays, "normal_indices", prefix))
    if shading_mode == 'CUSTOM' and normals is not None and len(normals) == len(fi):
        shading.set_custom_normals(mesh, normals)
    else:
        shading.flatten_inverted(mesh, starts)
    return mesh


def set_creases(mesh, crease_edges, sharpness):
    """Edge creases c = sqrt(s / 10) (clamped to 1) from OpenSubdiv sharpness on vertex pairs."""
    c = np.sqrt(np.clip(np.asarray(sharpness, dtype=np.float32) / SHARPNESS_INFINITE, 0.0, 1.0))
    values = attrs.edge_values(mesh, crease_edges, c)
    attr = mesh.attributes.get("crease_edge") or mesh.attributes.new("crease_edge", 'FLOAT', 'EDGE')
    attr.data.foreach_set("value", values)


def partition_mesh(name, cells_min, cells_max):
    """A wire mesh of boxes (8 vertices, 12 edges per cell) from `cells_min`/`cells_max`."""
    lo = np.asarray(cells_min, dtype=np.float32).reshape(-1, 3)
    hi = np.asarray(cells_max, dtype=np.float32).reshape(-1, 3)
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=bool)
    pts = np.where(corners[None, :, :], hi[:, None, :], lo[:, None, :]).reshape(-1, 3)
    box_edges = np.array([[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7],
                          [0, 4], [1, 5], [2, 6], [3, 7]], dtype=np.int32)
    edges = (box_edges[None, :, :] + 8 * np.arange(len(lo), dtype=np.int32)[:, None, None]).reshape(-1)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(pts))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(pts).reshape(-1))
    mesh.edges.add(len(edges) // 2)
    mesh.edges.foreach_set("vertices", np.ascontiguousarray(edges))
    mesh.update()
    return mesh


def frames_of(obj, scene, depsgraph, frame_start, frame_end):
    """A generator baking the evaluated object's vertex positions at every frame of
    [start, end]: yields the fraction done after each frame and returns them as [F, V, 3]
    (the scene's frame is restored afterwards, also when the generator is closed early).
    Raises ValueError when the vertex count changes."""
    current = scene.frame_current, scene.frame_subframe
    frames = []
    count = frame_end - frame_start + 1
    try:
        for f in range(frame_start, frame_end + 1):
            scene.frame_set(f)
            obj_eval = obj.evaluated_get(depsgraph)
            mesh = obj_eval.to_mesh()
            try:
                co = positions_of(mesh)
            finally:
                obj_eval.to_mesh_clear()
            if frames and len(co) != len(frames[0]):
                raise ValueError("its vertex count changes at frame %d (%d, was %d); an "
                                 "animation must keep one topology" % (f, len(co), len(frames[0])))
            frames.append(co)
            yield len(frames) / count
    finally:
        scene.frame_set(current[0], subframe=current[1])
    return np.stack(frames)
