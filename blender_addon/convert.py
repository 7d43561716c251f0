"""Blender meshes <-> the protocol's mesh arrays (docs/protocol.md, "Mesh arrays").

Everything goes through `foreach_get` / `foreach_set` and numpy, never a Python loop over
vertices, faces or corners (vertex group weights are the one exception: Blender has no bulk
access to them), so a million-triangle mesh converts in a fraction of a second.

Mapping:
- positions: vertex `co` (object space; the object's transform stays on the object);
- faces: corner vertex indices in face order (`face_indices`) and `loop_total` (`face_sizes`);
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


def positions_of(mesh):
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def _corner_order(mesh):
    """Corner indices in face order (Blender 4+ stores them so already; checked, not assumed)."""
    n_f = len(mesh.polygons)
    sizes = np.empty(n_f, dtype=np.int32)
    starts = np.empty(n_f, dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    mesh.polygons.foreach_get("loop_start", starts)
    offsets = np.zeros(n_f, dtype=np.int64)
    if n_f:
        np.cumsum(sizes[:-1], out=offsets[1:])
    if np.array_equal(starts, offsets):
        return sizes, None
    order = np.repeat(starts - offsets, sizes) + np.arange(int(sizes.sum()))
    return sizes, order


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
                   shape_keys=False):
    """The protocol arrays of `mesh`, the params they need (`group_names`) and what was sent
    besides the geometry (an :class:`attributes.Sent`, for rebuilding the results).

    `obj` gives the material slots (face groups are sent only when it has any) and the
    vertex groups; `normals` sends Blender's corner normals (to be carried as custom
    normals); `shape_keys` sends the mesh's shape keys (only meaningful for the object's own
    mesh, not an evaluated one)."""
    if len(mesh.polygons) == 0:
        raise ValueError("it has no faces")
    sizes, order = _corner_order(mesh)
    n_l = len(mesh.loops)
    corner_verts = np.empty(n_l, dtype=np.uint32)
    mesh.loops.foreach_get("vertex_index", corner_verts)
    if order is not None:
        corner_verts = corner_verts[order]
    arrays = {
        "positions": positions_of(mesh),
        "face_indices": corner_verts,
        "face_sizes": sizes.astype(np.uint32),
    }
    params = {}
    sent = attrs.Sent()
    if uvs and mesh.uv_layers.active is not None:
        # The active UV map travels as `uvs` (USD writes it as `st`); the others as
        # generic corner attributes.
        uv = np.empty(n_l * 2, dtype=np.float32)
        mesh.uv_layers.active.data.foreach_get("uv", uv)
        uv = uv.reshape(-1, 2)
        arrays["uvs"] = uv if order is None else uv[order]
        sent.uv_name = mesh.uv_layers.active.name
    if normals:
        nrm = np.empty(n_l * 3, dtype=np.float32)
        mesh.corner_normals.foreach_get("vector", nrm)
        nrm = nrm.reshape(-1, 3)
        arrays["normals"] = nrm if order is None else nrm[order]
    elif mesh.has_custom_normals:
        sent.dropped.append("custom normals (Blender's normals are used; choose Normals: "
                            "Custom to carry them)")
    if creases:
        attr = mesh.attributes.get("crease_edge")
        if attr is not None and attr.domain == 'EDGE' and len(mesh.edges):
            values = np.empty(len(mesh.edges), dtype=np.float32)
            attr.data.foreach_get("value", values)
            keep = values > 0.0
            if keep.any():
                c = np.minimum(values[keep], np.float32(1.0))
                arrays["crease_edges"] = attrs.edge_vertices(mesh)[keep].astype(np.uint32)
                arrays["crease_values"] = (c * c * np.float32(SHARPNESS_INFINITE)).astype(np.float32)
    if attributes:
        attrs.collect(mesh, obj, arrays, order, sent, skip={sent.uv_name} if sent.uv_name else ())
        if shape_keys:
            attrs.collect_shape_keys(mesh, arrays, sent)
    if obj is not None and len(obj.material_slots) > 0:
        mat = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get("material_index", mat)
        last = len(obj.material_slots) - 1
        arrays["face_groups"] = np.clip(mat, 0, last).astype(np.uint32)
        params["group_names"] = group_names_of(obj)
    return arrays, params, sent


def _get(arrays, name, prefix):
    return arrays.get(prefix + name)


def _per_corner(values, indices):
    if values is None:
        return None
    values = np.asarray(values)
    return values if indices is None else values[np.asarray(indices, dtype=np.int64)]


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
    pos = np.ascontiguousarray(_get(arrays, "positions", prefix), dtype=np.float32).reshape(-1, 3)
    fi = np.ascontiguousarray(_get(arrays, "face_indices", prefix), dtype=np.int32).reshape(-1)
    fs = _get(arrays, "face_sizes", prefix)
    fs = np.ascontiguousarray(fs, dtype=np.int32) if fs is not None else None
    if fs is None:  # [F, n] faces
        n = np.asarray(_get(arrays, "face_indices", prefix)).shape[-1]
        fs = np.full(len(fi) // n, n, dtype=np.int32)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(pos))
    mesh.vertices.foreach_set("co", pos.reshape(-1))
    mesh.loops.add(len(fi))
    mesh.loops.foreach_set("vertex_index", fi)
    mesh.polygons.add(len(fs))
    starts = np.zeros(len(fs), dtype=np.int32)
    if len(fs):
        np.cumsum(fs[:-1], out=starts[1:])
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.polygons.foreach_set("loop_total", fs)
    mesh.update(calc_edges=True)

    for mat in materials:
        mesh.materials.append(mat)
    groups = _get(arrays, "face_groups", prefix)
    if groups is not None and len(materials):
        idx = np.clip(np.asarray(groups, dtype=np.int32), 0, len(materials) - 1)
        mesh.polygons.foreach_set("material_index", np.ascontiguousarray(idx))

    uvs = _per_corner(_get(arrays, "uvs", prefix), _get(arrays, "uv_indices", prefix))
    uv_name = sent.uv_name if sent is not None and sent.uv_name else uv_name
    if uvs is not None and len(uvs) == len(fi):
        layer = mesh.uv_layers.new(name=uv_name)
        layer.data.foreach_set("uv", np.ascontiguousarray(uvs, dtype=np.float32).reshape(-1))
    elif sent is not None and sent.uv_name:
        sent.missing.add("UV map " + sent.uv_name)
    if sent is not None:
        sent.missing.update(attrs.apply_generic(mesh, arrays, prefix, sent))

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
        shading.flatten_inverted(mesh)
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
