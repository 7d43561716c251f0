#!/usr/bin/env python3
"""Builds the seed corpora of fuzz/corpus/<target>/ from the shared test data, the repository's
own test documents and hand-built frames (run from the repository root; rerun after a format
change, then `bash scripts/fuzz.sh cmin`). Needs `target/release/tessd` (compress, convert).

Every seed is at most 64 KiB: small files as they are, larger text files cut at a line break
(a truncated mesh is a seed for the readers' error paths), larger binaries left out.
"""
import glob
import hashlib
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED = os.environ.get("TESSD_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
TESSD = os.environ.get("TESSD_BIN", os.path.join(ROOT, "target", "release", "tessd"))
MAX = 64 * 1024
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def put(target, name, data):
    """Writes one seed (cut to 64 KiB at a line break when text)."""
    if len(data) > MAX:
        cut = data.rfind(b"\n", 0, MAX)
        data = data[: cut + 1] if cut > 0 else data[:MAX]
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def tessd(*args):
    subprocess.run([TESSD, *args], check=True, stdout=subprocess.DEVNULL)


def obj_mesh(path):
    """Positions and faces of an OBJ (first index of each corner)."""
    v, f = [], []
    for line in read(path).decode().splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            v.append(tuple(float(x) for x in t[1:4]))
        elif t[0] == "f":
            f.append([int(c.split("/")[0]) - 1 for c in t[1:]])
    return v, f


def ply_ascii(v, f, extra=False, uv=False):
    head = ["ply", "format ascii 1.0", "comment seed", f"element vertex {len(v)}",
            "property float x", "property float y", "property float z"]
    if extra:
        head += ["property float confidence", "property float intensity"]
    if uv:
        head += ["property float s", "property float t"]
    head += [f"element face {len(f)}", "property list uchar int vertex_indices", "end_header"]
    rows = []
    for i, p in enumerate(v):
        r = list(p) + ([1.0, 0.5] if extra else []) + ([i % 7 / 7, i % 5 / 5] if uv else [])
        rows.append(" ".join(f"{x:g}" for x in r))
    rows += [" ".join(str(x) for x in [len(face)] + face) for face in f]
    return ("\n".join(head + rows) + "\n").encode()


def ply_binary(v, f, big=False, normals=False):
    e = ">" if big else "<"
    head = ["ply", f"format binary_{'big' if big else 'little'}_endian 1.0",
            f"element vertex {len(v)}", "property float x", "property float y", "property float z"]
    if normals:
        head += ["property float nx", "property float ny", "property float nz"]
    head += [f"element face {len(f)}", "property list uchar uint vertex_indices", "end_header"]
    out = bytearray(("\n".join(head) + "\n").encode())
    for p in v:
        out += struct.pack(e + "3f", *p)
        if normals:
            out += struct.pack(e + "3f", 0.0, 0.0, 1.0)
    for face in f:
        out += struct.pack(e + "B", len(face)) + struct.pack(e + f"{len(face)}I", *face)
    return bytes(out)


def triangles(v, f):
    for face in f:
        for k in range(1, len(face) - 1):
            yield v[face[0]], v[face[k]], v[face[k + 1]]


def stl_ascii(v, f):
    out = ["solid seed"]
    for a, b, c in triangles(v, f):
        out += ["  facet normal 0 0 1", "    outer loop"]
        out += [f"      vertex {p[0]:g} {p[1]:g} {p[2]:g}" for p in (a, b, c)]
        out += ["    endloop", "  endfacet"]
    out.append("endsolid seed")
    return ("\n".join(out) + "\n").encode()


def stl_binary(v, f):
    tris = list(triangles(v, f))
    out = bytearray(b"seed binary stl".ljust(80, b"\0")) + struct.pack("<I", len(tris))
    for t in tris:
        out += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0"
    return bytes(out)


def off_text(v, f, head="OFF"):
    rows = [head, f"{len(v)} {len(f)} 0"]
    for p in v:
        extra = " 0 0 1" if head == "NOFF" else (" 1 0 0 1" if head == "COFF" else "")
        rows.append(f"{p[0]:g} {p[1]:g} {p[2]:g}{extra}")
    rows += [" ".join(str(x) for x in [len(face)] + face) for face in f]
    return ("\n".join(rows) + "\n").encode()


def frame(obj, arrays=()):
    """One protocol frame: header, JSON, payload (arrays 8-byte aligned)."""
    table, payload = [], bytearray()
    for name, dtype, shape, data in arrays:
        table.append({"name": name, "dtype": dtype, "shape": shape, "offset": len(payload),
                      "length": len(data)})
        payload += data + b"\0" * (-len(data) % 8)
    if arrays:
        obj = dict(obj, arrays=table)
    j = json.dumps(obj, separators=(",", ":")).encode()
    head = b"TSSD" + struct.pack("<HHIIQ", 1, 0, len(j), 0, len(payload))
    return head + j + bytes(payload)


def envelope_seeds(frames):
    """Requests for the envelope target: the frame seeds that are requests, the built-in ops'
    parameters, and envelopes each wrong in one member."""
    for name in ["hello", "stats_path", "stats_arrays", "all_dtypes", "cancel"]:
        put("envelope", name, frames[name])
    requests = {
        "hold": {"id": 5, "op": "session.hold", "params": {"pid": 4242, "host": "blender"}},
        "release_bad_pid": {"id": 6, "op": "session.release", "params": {"pid": -1}},
        "shutdown_if_unheld": {"id": 7, "op": "shutdown", "params": {"if_unheld": True}},
        "shutdown_bad_flag": {"id": 8, "op": "shutdown", "params": {"if_unheld": "yes"}},
        "unknown_op": {"id": 9, "op": "mesh.explode", "params": None},
        "id_negative": {"id": -3, "op": "ping"},
        "id_float": {"id": 1.5, "op": "ping", "params": {"echo": "x"}},
        "op_number": {"id": 10, "op": 17},
        "params_array": {"id": 11, "op": "simplify", "params": [1, 2]},
        "no_id": {"op": "hello"},
    }
    for name, obj in requests.items():
        put("envelope", name, frame(obj))
    put("envelope", "hold_then_release", frame(requests["hold"])
        + frame({"id": 12, "op": "session.release", "params": {"pid": 4242}}))


def small_meshes():
    """(name, positions, faces) of small shared meshes."""
    out = []
    for p in ["mesh/draco_non_manifold_wrap.obj", "mesh/draco_test_nm.obj",
              "mesh/spot_control_mesh.obj", "subdiv/catmark_cube_level0.obj",
              "subdiv/loop_icosahedron_level0.obj", "subdiv/catmark_edgecorner_level0.obj"]:
        v, f = obj_mesh(os.path.join(SHARED, p))
        out.append((os.path.splitext(os.path.basename(p))[0], v, f))
    return out


def main():
    if os.path.isdir(CORPUS) and "--force" not in sys.argv:
        sys.exit(f"{CORPUS} exists; pass --force to rebuild it")
    shutil.rmtree(CORPUS, ignore_errors=True)
    meshes = small_meshes()
    tmp = tempfile.mkdtemp()

    # OBJ: the shared OBJs, large ones cut to 64 KiB at a line break.
    for p in sorted(glob.glob(os.path.join(SHARED, "mesh", "*.obj"))
                    + glob.glob(os.path.join(SHARED, "subdiv", "*level0.obj"))
                    + glob.glob(os.path.join(SHARED, "subdiv", "*level1.obj"))):
        put("mesh_obj", os.path.basename(p), read(p))
    put("mesh_obj", "groups_uv_normals.obj", b"# seed\no part\nv 0 0 0\nv 1 0 0\nv 1 1 0\n"
        b"v 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng top\nusemtl red\n"
        b"f 1/1/1 2/2/1 3/3/1 4/4/1\ns 1\nf -4//1 -2//1 -1//1\nl 1 2\n")

    # PLY: the shared bunny cut; ASCII with extra properties and UVs; binary both byte orders.
    put("mesh_ply", "bun_zipper_head.ply", read(os.path.join(SHARED, "mesh", "bun_zipper.ply")))
    for name, v, f in meshes[:4]:
        put("mesh_ply", f"{name}_ascii.ply", ply_ascii(v, f, extra=name.startswith("draco")))
        put("mesh_ply", f"{name}_le.ply", ply_binary(v, f, normals=name.startswith("spot")))
    name, v, f = meshes[3]
    put("mesh_ply", f"{name}_be.ply", ply_binary(v, f, big=True))
    put("mesh_ply", f"{name}_uv.ply", ply_ascii(v, f, uv=True))
    for name, src in [("suzanne", "mesh/suzanne.obj"), ("double_torus", "mesh/double_torus.off")]:
        out = os.path.join(tmp, name + ".ply")
        tessd("convert", os.path.join(SHARED, src), out)
        put("mesh_ply", f"{name}_tessd.ply", read(out))

    # STL: ASCII and binary of the small meshes, and tessd's own binary output.
    for name, v, f in meshes[:4]:
        put("mesh_stl", f"{name}_ascii.stl", stl_ascii(v, f))
        put("mesh_stl", f"{name}_binary.stl", stl_binary(v, f))
    out = os.path.join(tmp, "suzanne.stl")
    tessd("convert", os.path.join(SHARED, "mesh", "suzanne.obj"), out)
    put("mesh_stl", "suzanne_tessd.stl", read(out))

    # OFF: the shared OFFs, and each header variant.
    for p in sorted(glob.glob(os.path.join(SHARED, "mesh", "*.off"))):
        put("mesh_off", os.path.basename(p), read(p))
    name, v, f = meshes[2]
    for head in ["OFF", "COFF", "NOFF"]:
        put("mesh_off", f"{name}_{head.lower()}.off", off_text(v, f, head))

    # B-Rep documents: the repository's test documents (each ≤ 64 KiB whole; larger ones are
    # left out rather than cut, a cut JSON document is only a syntax error).
    docs = (glob.glob(os.path.join(ROOT, "core", "brep", "tests", "data", "*.json"))
            + glob.glob(os.path.join(ROOT, "core", "brep", "tests", "data", "occt", "*.json"))
            + glob.glob(os.path.join(ROOT, "core", "tessellate", "tests", "data", "*.json"))
            + glob.glob(os.path.join(ROOT, "core", "trim", "tests", "data", "*.json")))
    for p in sorted(docs):
        if os.path.getsize(p) <= MAX:
            put("brep", os.path.basename(p), read(p))
    put("brep", "plane.json", json.dumps({
        "format": "tessd-brep", "version": 1, "units": "mm",
        "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 0],
                                        "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]},
                   "bounds": [0, 1, 0, 1]}]}).encode())

    # Job files: the examples, and each shape the reader takes.
    for p in sorted(glob.glob(os.path.join(ROOT, "examples", "jobs", "*.json"))):
        put("job_file", os.path.basename(p), read(p))
    put("job_file", "single.json", b'{"op": "mesh.stats", "params": {"input": "a.obj"}}')
    put("job_file", "no_params.json", b'{"op": "debug.echo"}')
    put("job_file", "jobs.json", b'{"jobs": [{"op": "mesh.stats"}, {"op": "simplify", '
        b'"params": {"input": "a.ply", "output": "b.obj", "target_vertices": "20%"}}]}')

    # Render parameters: the params objects of the examples and docs.
    renders = [
        {"input": "part.json", "output": "part.png", "view": "iso", "size": "960x540"},
        {"input": "bunny.ply", "output": "bunny.png", "eye": [0.25, 0.2, 0.45], "up": [0, 1, 0],
         "size": "960x540", "shading": "gooch"},
        {"input": "a.obj", "size": [640, 480], "view": "top", "fov": 45, "edges": True,
         "shading": "toon"},
        {"input": "a.obj", "output": "t.png", "turntable": 12, "view": "front",
         "face_ids": "ids.png", "shading": "face-ids"},
        {"brep": {}, "cracks": "image", "raycast": False, "eye": [3, 0, 0],
         "target": [0, 0, 0], "tolerance": "0.05%"},
        {"input": ["a.obj", "b.obj", "c.obj"], "columns": 2, "size": "320x240",
         "view": "bottom", "cracks": "none"},
    ]
    for i, r in enumerate(renders):
        put("render_params", f"render_{i}.json", json.dumps(r).encode())

    # Frames: requests and replies as the daemon and clients send them.
    cube_v, cube_f = meshes[3][1], meshes[3][2]
    pos = b"".join(struct.pack("<3f", *p) for p in cube_v)
    idx = b"".join(struct.pack("<I", i) for face in cube_f for i in face)
    sizes = b"".join(struct.pack("<I", len(face)) for face in cube_f)
    frames = {
        "hello": frame({"id": 1, "op": "hello"}),
        "stats_path": frame({"id": 7, "op": "mesh.stats", "params": {"input": "/data/a.ply"},
                             "arrays": []}),
        "stats_arrays": frame({"id": 2, "op": "mesh.stats", "params": {}}, [
            ("positions", "f32", [len(cube_v), 3], pos),
            ("face_indices", "u32", [len(idx) // 4], idx),
            ("face_sizes", "u32", [len(cube_f)], sizes)]),
        "all_dtypes": frame({"id": 3, "op": "debug.echo", "params": {"echo": [1, "x"]}}, [
            (f"a_{d}", d, [3], bytes(range(3 * s))) for d, s in
            [("u8", 1), ("u16", 2), ("u32", 4), ("u64", 8), ("i32", 4), ("i64", 8),
             ("f32", 4), ("f64", 8)]]),
        "cancel": frame({"id": 4, "op": "cancel", "params": {"id": 2}}),
        "reply_ok": frame({"id": 7, "type": "ok", "result": {"faces": 69451}, "arrays": [],
                           "files": [], "elapsed_ms": 41.7}),
        "progress": frame({"id": 7, "type": "progress",
                           "progress": {"fraction": 0.5, "stage": "read", "message": ""}}),
    }
    for name, data in frames.items():
        put("frame", name, data)
    put("frame", "two_frames", frames["hello"] + frames["cancel"])
    envelope_seeds(frames)

    # Codec: small meshes compressed as the brief of the CI step says, and one with --ahead 1.
    codec = [(os.path.join(SHARED, "mesh", "spot_control_mesh.obj"), []),
             (os.path.join(SHARED, "mesh", "suzanne.obj"), []),
             (os.path.join(SHARED, "mesh", "double_torus.off"), []),
             (os.path.join(SHARED, "subdiv", "loop_icosahedron_level1.obj"), []),
             (os.path.join(SHARED, "mesh", "mpi_polygons.off"), ["--ahead", "1"])]
    for src, extra in codec:
        out = os.path.join(tmp, os.path.splitext(os.path.basename(src))[0] + ".tsc")
        tessd("compress", src, out, "--bits", "10", "--min-cell", "500", "--cell-split", "2",
              "--root-bits", "4", *extra)
        data = read(out)
        if len(data) <= MAX:
            put("codec", os.path.basename(out).replace(".tsc", "_ahead1.tsc" if extra else ".tsc"),
                data)
    shutil.rmtree(tmp)

    for t in sorted(os.listdir(CORPUS)):
        files = os.listdir(os.path.join(CORPUS, t))
        size = sum(os.path.getsize(os.path.join(CORPUS, t, f)) for f in files)
        print(f"{t:14} {len(files):3} seeds {size / 1024:8.1f} KiB")


if __name__ == "__main__":
    main()
