"""Round-trip time of Simplify on a ~1.3 M-triangle object, from the operator call to the new
object, split into Blender export (mesh -> arrays), transfer, daemon work and Blender import
(arrays -> mesh). Not a test: run it by hand with a daemon binary built,

    .venv/bin/python tests/blender_addon/roundtrip_timing.py [--subdivisions 9]

Transfer is measured with `debug.echo` on the same arrays (the protocol cost alone, input
and output); daemon work is the request's round trip minus that transfer.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent), str(HERE.parent / "daemon"), str(HERE.parents[1] / "python")]
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="tessd-blender-user-"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--subdivisions", type=int, default=9, help="ico sphere subdivisions (9: 1.31 M triangles)")
    ap.add_argument("--target", default="10%")
    args = ap.parse_args()

    import subprocess

    import bpy

    import locate
    from addon_env import ADDON, install_addon
    from daemon_util import DaemonProcess, short_tmpdir

    out = Path(tempfile.mkdtemp())
    subprocess.run([sys.executable, str(HERE.parents[1] / "blender_addon" / "build.py"), "--out",
                    str(out), "--no-validate"], check=True, stdout=subprocess.DEVNULL)
    with short_tmpdir() as d:
        proc = DaemonProcess(str(locate.tessd_bin()), os.path.join(d, "t.sock")).start()
        try:
            addon = install_addon(next(out.glob("*.zip")), out / "repo", proc.socket)
            convert = sys.modules[ADDON + ".convert"]
            tessd = sys.modules[ADDON + ".client"].tessd
            bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=args.subdivisions)
            obj = bpy.context.object
            tris = len(obj.data.polygons)

            t0 = time.perf_counter()
            assert bpy.ops.tessd.simplify(method='COMPLEXITY', target=float(args.target.rstrip("%")),
                                          target_is_percent=True) == {'FINISHED'}
            total = time.perf_counter() - t0

            # the same steps one by one
            t0 = time.perf_counter()
            arrays, params = convert.mesh_to_arrays(obj.data, obj)
            t_export = time.perf_counter() - t0
            params = dict(params, method="complexity", target_vertices=args.target,
                          representative="barycenter", triangulate=False, preserve_boundaries=False)
            with tessd.Client(proc.socket) as c:
                t0 = time.perf_counter()
                _res, reply = c.call("simplify", params, arrays)
                t_request = time.perf_counter() - t0
                t0 = time.perf_counter()
                c.call("debug.echo", {}, arrays)
                c.call("debug.echo", {}, reply)
                t_transfer = time.perf_counter() - t0
            t0 = time.perf_counter()
            mesh = convert.mesh_from_arrays("timing", reply)
            t_import = time.perf_counter() - t0
            bpy.data.meshes.remove(mesh)
            mb = sum(a.nbytes for a in arrays.values()) / 2 ** 20
            print("Simplify %s of %d triangles (%.0f MiB of arrays sent), Blender %s:"
                  % (args.target, tris, mb, bpy.app.version_string))
            print("  operator, call to new object: %7.3f s" % total)
            print("  Blender export (foreach_get): %7.3f s" % t_export)
            print("  transfer (debug.echo, in+out):%7.3f s" % t_transfer)
            print("  daemon work (request - transfer): %5.3f s" % max(0.0, t_request - t_transfer))
            print("  Blender import (foreach_set): %7.3f s" % t_import)
            del addon
        finally:
            proc.stop()


if __name__ == "__main__":
    main()
