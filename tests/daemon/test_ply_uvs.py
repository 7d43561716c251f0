"""A PLY written by `mesh.convert` carries the UVs of a mesh with UV seams, read back by an
independent reader (Blender's own PLY importer through bpy): every face corner has the UV the
OBJ gave it, the vertices at the seams split in two (as exporters do)."""

from __future__ import annotations

import numpy as np

import tessd


def obj_corner_uvs(path):
    """Per face corner, the `vt` the OBJ file gives it (the file's own text, parsed here)."""
    vt, corners = [], []
    for line in open(path, encoding="utf-8"):
        t = line.split()
        if not t:
            continue
        if t[0] == "vt":
            vt.append((float(t[1]), float(t[2])))
        elif t[0] == "f":
            for c in t[1:]:
                corners.append(vt[int(c.split("/")[1]) - 1])
    return np.asarray(corners, dtype=np.float32)


def test_ply_uvs_read_back_by_blender(daemon, shared_data, tmp_path):
    import bpy
    source = shared_data / "mesh" / "spot_triangulated.obj"
    out = tmp_path / "spot.ply"
    with tessd.Client(daemon.socket, timeout=60) as c:
        result, _ = c.call("mesh.convert", {"input": str(source), "output": str(out)})
    assert result["dropped_attributes"] == []
    assert result["written"] == {"vertices": 3225, "faces": 5856, "triangulated": False,
                                 "split_vertices": 295}

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.ply_import(filepath=str(out))
    obj = bpy.context.selected_objects[0]
    me = obj.data
    assert (len(me.vertices), len(me.polygons)) == (3225, 5856)
    assert len(me.uv_layers) == 1, "Blender found no UVs in the PLY"
    uv = np.empty(2 * len(me.loops), dtype=np.float32)
    me.uv_layers[0].data.foreach_get("uv", uv)
    uv = uv.reshape(-1, 2)
    expected = obj_corner_uvs(source)
    assert uv.shape == expected.shape
    err = float(np.abs(uv - expected).max())
    print(f"PLY UVs read by Blender {bpy.app.version_string}: {len(uv)} corners, max error {err:g}")
    assert err <= 1e-6
