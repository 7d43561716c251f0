"""The Blender add-on, driven headless from a script.

Builds the add-on's extension zip (blender_addon/build.py), installs it the way Blender's
"Install from Disk" does into a throw-away Blender configuration, and calls its operators by
their bl_idname, as any script can: `tessd.simplify` (the Stanford bunny to 10 % of its
vertices), `tessd.generate_lods` (50 %, 20 %, 5 %, also written as `bunny_lods.usda`) and
`tessd.subdivide` (Suzanne, Catmull-Clark, 2 levels). It prints each result's counts and saves
the scene as `blender_headless.blend`.

Run (Blender 5.0's `bpy` module, the `.venv` of scripts/setup.sh; the daemon from $TESSD_BIN or
PATH; the bunny from $TESSD_SHARED_DATA/mesh):

    .venv/bin/python examples/blender_headless.py [OUT_DIR]      # default ./tessd-examples-out
"""

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.environ.get("TESSD_SHARED_DATA") or os.path.join(REPO, "..", "shared", "data")
out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "tessd-examples-out")
os.makedirs(out, exist_ok=True)

# Blender's user configuration in a throw-away folder (before bpy is imported).
work = tempfile.mkdtemp(prefix="tessd-blender-")
os.environ["BLENDER_USER_RESOURCES"] = work
import bpy  # noqa: E402
import addon_utils  # noqa: E402

# Use the installed tessd package, else the one in this repository's python/ folder.
if importlib.util.find_spec("tessd") is None:
    sys.path.insert(0, os.path.join(REPO, "python"))
import tessd  # noqa: E402
from tessd.daemon import find_binary  # noqa: E402


def select(obj):
    """Makes `obj` the only selected object, and the active one (operators act on those)."""
    for o in bpy.context.view_layer.objects:
        o.select_set(o == obj)
    bpy.context.view_layer.objects.active = obj


def counts(obj):
    return "%d vertices, %d faces" % (len(obj.data.vertices), len(obj.data.polygons))


sock = tessd.ensure_daemon(os.path.join(work, "d.sock"))  # a private daemon, stopped below
try:
    # The extension zip, bundling the same daemon binary, installed into a local repository.
    build = os.path.join(REPO, "blender_addon", "build.py")
    subprocess.run([sys.executable, build, "--no-validate", "--binary", find_binary(),
                    "--out", work], check=True, stdout=subprocess.DEVNULL)
    [zip_name] = [f for f in os.listdir(work) if f.endswith(".zip")]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    prefs = bpy.context.preferences
    prefs.extensions.repos.new(name="examples", module="examples",
                               custom_directory=os.path.join(work, "extensions"), source='USER')
    bpy.ops.extensions.package_install_files(filepath=os.path.join(work, zip_name),
                                             repo="examples", enable_on_install=True)
    addon = prefs.addons["bl_ext.examples.tessd"].preferences
    addon.socket, addon.auto_start = sock, False  # use our daemon, start none

    bpy.ops.wm.ply_import(filepath=os.path.join(DATA, "mesh", "bun_zipper.ply"))
    bunny = bpy.context.object
    bunny.name = "bunny"
    print("bunny:", counts(bunny))

    select(bunny)
    bpy.ops.tessd.simplify(method='COMPLEXITY', target=10, target_is_percent=True)
    print("tessd.simplify ->", bpy.context.object.name, counts(bpy.context.object))

    select(bunny)
    bpy.ops.tessd.generate_lods(levels="50%,20%,5%", usd_path=os.path.join(out, "bunny_lods.usda"))
    for lod in bpy.data.collections["bunny_LODs"].objects:
        print("tessd.generate_lods ->", lod.name, counts(lod))

    bpy.ops.mesh.primitive_monkey_add(location=(0.5, 0, 0), size=0.1)
    suzanne = bpy.context.object
    select(suzanne)
    bpy.ops.tessd.subdivide(scheme='CATMULL_CLARK', levels=2)
    print("tessd.subdivide ->", bpy.context.object.name, counts(suzanne), "->",
          counts(bpy.context.object))

    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "blender_headless.blend"))
    print("saved", os.path.join(out, "blender_headless.blend"))
    addon_utils.disable("bl_ext.examples.tessd")  # releases the daemon
finally:
    tessd.stop_daemon(sock)
    shutil.rmtree(work, ignore_errors=True)
