"""Builds the installable extension zip: `python3 blender_addon/build.py` ->
blender_addon/dist/tessd-<version>.zip.

The zip holds the add-on's files and, as the subpackage `vendor/tessd`, a copy of the
`tessd` Python client made from python/tessd at build time (the add-on folder in git keeps no
copy of it). When Blender's own extension tool is at hand (the `bpy` module's
`bl_pkg/cli/blender_ext.py`, what `blender --command extension validate` runs), the zip is
validated with it; `--no-validate` skips that, `--blender-ext PATH` names the tool.
"""

import argparse
import glob
import os
import re
import subprocess
import sys
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
CLIENT = os.path.join(REPO, "python", "tessd")
#: Files of the add-on folder that are not part of the extension.
EXCLUDE = {"build.py"}


def manifest_version():
    with open(os.path.join(HERE, "blender_manifest.toml"), encoding="utf-8") as f:
        m = re.search(r'^version\s*=\s*"([^"]+)"', f.read(), re.M)
    if not m:
        raise SystemExit("blender_manifest.toml has no version")
    return m.group(1)


def addon_files():
    """(path on disk, name in the zip) of the add-on's own files."""
    out = [(os.path.join(HERE, "blender_manifest.toml"), "blender_manifest.toml")]
    for name in sorted(os.listdir(HERE)):
        if name.endswith(".py") and name not in EXCLUDE:
            out.append((os.path.join(HERE, name), name))
    for name in sorted(os.listdir(CLIENT)):
        if name.endswith(".py"):
            out.append((os.path.join(CLIENT, name), "vendor/tessd/" + name))
    return out


VENDOR_INIT = ('"""Third-party code bundled at build time: the tessd client (python/tessd '
               'in the tessd repository)."""\n')


def build(out_dir):
    version = manifest_version()
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "tessd-%s.zip" % version)
    tmp = path + ".tmp"
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for src, name in addon_files():
            z.write(src, name)
        z.writestr("vendor/__init__.py", VENDOR_INIT)
    os.replace(tmp, path)
    return path


def find_blender_ext():
    pattern = os.path.join(REPO, ".venv", "lib", "python3*", "site-packages", "bpy", "*",
                           "scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")
    hits = sorted(glob.glob(pattern))
    return hits[-1] if hits else None


def validate(zip_path, tool):
    """Runs Blender's `extension validate` on the zip; returns its exit status."""
    proc = subprocess.run([sys.executable, tool, "validate", zip_path],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    sys.stdout.write(proc.stdout)
    return proc.returncode


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(HERE, "dist"), help="output folder")
    ap.add_argument("--no-validate", action="store_true")
    ap.add_argument("--blender-ext", help="path of Blender's bl_pkg/cli/blender_ext.py")
    args = ap.parse_args(argv)
    path = build(args.out)
    print(path)
    if not args.no_validate:
        tool = args.blender_ext or find_blender_ext()
        if tool is None:
            print("not validated: Blender's blender_ext.py not found (install bpy in .venv, or "
                  "run `blender --command extension validate %s`)" % path)
        elif validate(path, tool) != 0:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
