"""Shading of results: Blender's own normals by default, custom normals on request, and
never a corner normal facing away from its face.

Simplification folds faces: a cell's representative can leave a face tilted far from its
neighbours, and a smooth corner normal (the average over its fan) then points more than
90° away from that face. Blender shades such a corner black (the "specks" on a LOD chain).
Blender's own tools avoid it by splitting normals at sharp faces and edges, so:

- by default the result's normals are Blender's: the input's `sharp_face` and
  `sharp_edge` come back through the clustering (a result face is flat when its source
  face was), and any face that still has a corner more than 90° from its own normal is
  made flat, which also takes it out of its neighbours' fans; repeated until none is left;
- with custom normals (the input's corner normals averaged per cell, `normals` in the
  protocol), a corner more than 90° from its face gets the face's normal.
"""

import bpy
import numpy as np

#: A corner whose normal is more than this from its face's normal is a black speck.
LIMIT_COS = 0.0


def corner_faces(mesh, starts=None):
    """The face of every corner. `starts` (the faces' first corners, as the mesh was built
    from) saves reading them back; without it they are read."""
    n_f, n_l = len(mesh.polygons), len(mesh.loops)
    if n_l == 3 * n_f:  # triangles only (a face has at least 3 corners)
        return np.arange(n_l, dtype=np.int64) // 3
    if starts is None:
        starts = np.empty(n_f, dtype=np.int32)
        mesh.polygons.foreach_get("loop_start", starts)
    sizes = np.diff(np.asarray(starts, dtype=np.int64), append=n_l)
    return np.repeat(np.arange(n_f), sizes)


def face_normals(mesh):
    """Blender's face normals, f32 [F, 3] (`polygon_normals` copies them in one go;
    `polygons`' `normal` would go element by element)."""
    n = np.empty(len(mesh.polygons) * 3, dtype=np.float32)
    mesh.polygon_normals.foreach_get("vector", n)
    return n.reshape(-1, 3)


def corner_normals(mesh):
    n = np.empty(len(mesh.loops) * 3, dtype=np.float32)
    mesh.corner_normals.foreach_get("vector", n)
    return n.reshape(-1, 3)


def inverted_corners(mesh, faces=None):
    """Boolean per corner: its normal is more than 90° from its face's normal (`faces`: the
    face of every corner, :func:`corner_faces`)."""
    if not len(mesh.loops):
        return np.zeros(0, dtype=bool)
    if faces is None:
        faces = corner_faces(mesh)
    dots = np.einsum("ij,ij->i", corner_normals(mesh), face_normals(mesh)[faces])
    return dots < LIMIT_COS


def flatten_inverted(mesh, starts=None, max_rounds=64):
    """Makes flat every face with an inverted corner until none is left; returns how many
    faces were made flat. Flat faces get their own normal at every corner, and Blender's
    smooth fans stop at them, so each round can only improve the faces around. `starts`:
    see :func:`corner_faces`."""
    flat = np.zeros(len(mesh.polygons), dtype=bool)
    attr = mesh.attributes.get("sharp_face")
    if attr is not None and attr.domain == 'FACE':
        attr.data.foreach_get("value", flat)
    if flat.all():  # a flat face's corners have its own normal: nothing can be inverted
        return 0
    made = 0
    faces = corner_faces(mesh, starts)
    for _ in range(max_rounds):
        bad = inverted_corners(mesh, faces)
        if not bad.any():
            break
        new = np.zeros(len(flat), dtype=bool)
        new[faces[bad]] = True
        new &= ~flat
        if not new.any():
            break
        flat |= new
        made += int(new.sum())
        set_sharp_faces(mesh, flat)
    return made


def set_sharp_faces(mesh, flags, update=True):
    attr = mesh.attributes.get("sharp_face") or mesh.attributes.new("sharp_face", 'BOOLEAN', 'FACE')
    attr.data.foreach_set("value", np.ascontiguousarray(flags, dtype=bool))
    if update:
        mesh.update()


def set_custom_normals(mesh, normals):
    """Custom normals, one per corner, with any corner facing away from its face replaced by
    the face's normal; returns how many were replaced. Every face is smooth (custom
    normals apply to smooth faces)."""
    normals = np.asarray(normals, dtype=np.float32).reshape(-1, 3).copy()
    fn = face_normals(mesh)[corner_faces(mesh)]
    bad = np.einsum("ij,ij->i", normals, fn) < LIMIT_COS
    normals[bad] = fn[bad]
    set_sharp_faces(mesh, np.zeros(len(mesh.polygons), dtype=bool))
    if bpy.app.version >= (4, 5, 0):
        attr = mesh.attributes.get("custom_normal") or mesh.attributes.new(
            "custom_normal", 'FLOAT_VECTOR', 'CORNER')
        attr.data.foreach_set("vector", np.ascontiguousarray(normals).reshape(-1))
    else:  # pragma: no cover - Blender 4.2-4.4
        mesh.normals_split_custom_set(normals)
    mesh.update()
    return int(bad.sum())
