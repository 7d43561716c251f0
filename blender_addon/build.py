"""Builds the installable extension zip for one platform: `python3 blender_addon/build.py` ->
blender_addon/dist/tessd-<version>-<platform>.zip (e.g. tessd-0.1.0-linux-x64.zip).

The zip holds the add-on's files, as the subpackage `vendor/tessd` a copy of the `tessd`
Python client made from python/tessd at build time (the add-on folder in git keeps no copy of
it), and the daemon itself at `bin/tessd` (`bin/tessd.exe` for Windows), so that an artist who
installs the zip needs nothing else: a Blender started from a desktop launcher has no shell
PATH and no TESSD_BIN. A compiled binary runs on one platform only, hence one zip per platform
as `blender --command extension build --split-platforms` makes them: the zip's copy of
blender_manifest.toml gets `platforms = ["<platform>"]` (Blender refuses to install it
elsewhere; the manifest in git lists none). `--binary PATH` names the daemon (default the
release build in cargo's target folder, $CARGO_TARGET_DIR or target/, which must exist:
`cargo build --release -p tessd`), `--platform` its platform (default this machine's, in
Blender's spelling: linux-x64, linux-arm64, macos-arm64, macos-x64, windows-x64). Blender's installer extracts with Python's
zipfile, which drops permission bits, so the add-on makes bin/tessd executable before running
it; the zip still records mode 0755 for tools that honour it.

When Blender's own extension tool is at hand (the `bpy` module's
`bl_pkg/cli/blender_ext.py`, what `blender --command extension validate` runs), the zip is
validated with it; `--no-validate` skips that, `--blender-ext PATH` names the tool.
"""

import argparse
import glob
import os
import platform as _platform
import re
import stat
import subprocess
import sys
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
CLIENT = os.path.join(REPO, "python", "tessd")
#: Files of the add-on folder that are not part of the extension.
EXCLUDE = {"build.py"}


#: Blender's platform names (`platforms` in the manifest) that this build knows.
PLATFORMS = ("linux-x64", "linux-arm64", "macos-arm64", "macos-x64", "windows-x64",
             "windows-arm64")


def this_platform():
    """This machine's platform in Blender's spelling (as bl_pkg's platform_from_this_system)."""
    system = _platform.system().lower()
    system = {"darwin": "macos"}.get(system, system)
    machine = _platform.machine().lower()
    machine = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64"}.get(machine, machine)
    return "%s-%s" % (system, machine)


def binary_name(platform):
    """Where the daemon goes in the zip (and where the add-on looks for it)."""
    return "bin/tessd.exe" if platform.startswith("windows-") else "bin/tessd"


def default_binary(platform):
    """The release build of this checkout (cargo's target folder: $CARGO_TARGET_DIR when set,
    as cargo itself reads it, else the repository's target/)."""
    target = os.environ.get("CARGO_TARGET_DIR") or os.path.join(REPO, "target")
    return os.path.join(os.path.abspath(target), "release",
                        "tessd.exe" if platform.startswith("windows-") else "tessd")


def read_manifest():
    with open(os.path.join(HERE, "blender_manifest.toml"), encoding="utf-8") as f:
        return f.read()


def manifest_version(text=None):
    m = re.search(r'^version\s*=\s*"([^"]+)"', read_manifest() if text is None else text, re.M)
    if not m:
        raise SystemExit("blender_manifest.toml has no version")
    return m.group(1)


def manifest_for(platform, text=None):
    """The manifest with `platforms = ["<platform>"]` as a top-level key: it replaces a
    `platforms` line the manifest may have, else goes before the first table (TOML keys after
    a `[table]` header would belong to that table)."""
    text = read_manifest() if text is None else text
    line = 'platforms = ["%s"]' % platform
    if re.search(r"^platforms\s*=.*$", text, re.M):
        return re.sub(r"^platforms\s*=.*$", line, text, count=1, flags=re.M)
    m = re.search(r"^\[", text, re.M)
    at = m.start() if m else len(text)
    head = text[:at]
    if head and not head.endswith("\n"):
        head += "\n"
    return head + line + "\n" + ("\n" if m else "") + text[at:]


def addon_files():
    """(path on disk, name in the zip) of the add-on's own files."""
    out = []
    for name in sorted(os.listdir(HERE)):
        if name.endswith(".py") and name not in EXCLUDE:
            out.append((os.path.join(HERE, name), name))
    for name in sorted(os.listdir(CLIENT)):
        if name.endswith(".py"):
            out.append((os.path.join(CLIENT, name), "vendor/tessd/" + name))
    return out


VENDOR_INIT = ('"""Third-party code bundled at build time: the tessd client (python/tessd '
               'in the tessd repository)."""\n')


def _check_binary(binary):
    if not os.path.isfile(binary):
        raise SystemExit("build.py: the tessd binary %s does not exist; build it with "
                         "`cargo build --release -p tessd` or pass --binary PATH" % binary)
    if not os.access(binary, os.X_OK) and not binary.lower().endswith(".exe"):
        raise SystemExit("build.py: %s is not executable" % binary)


def build(out_dir, binary=None, platform=None):
    """Writes tessd-<version>-<platform>.zip into ``out_dir``; returns its path."""
    platform = platform or this_platform()
    binary = binary or default_binary(platform)
    _check_binary(binary)
    manifest = read_manifest()
    version = manifest_version(manifest)
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "tessd-%s-%s.zip" % (version, platform))
    tmp = path + ".tmp"
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("blender_manifest.toml", manifest_for(platform, manifest))
        for src, name in addon_files():
            z.write(src, name)
        z.writestr("vendor/__init__.py", VENDOR_INIT)
        info = zipfile.ZipInfo.from_file(binary, binary_name(platform))
        # A regular file, rwxr-xr-x, whatever the mode on disk (unzip and most tools honour it).
        info.external_attr = (stat.S_IFREG | 0o755) << 16
        info.compress_type = zipfile.ZIP_DEFLATED
        with open(binary, "rb") as src, z.open(info, "w") as dst:
            while True:
                chunk = src.read(1 << 20)
                if not chunk:
                    break
                dst.write(chunk)
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
    ap.add_argument("--binary", help="the tessd executable to bundle as bin/tessd (default: "
                                     "release/tessd in $CARGO_TARGET_DIR or this repository's target/)")
    ap.add_argument("--platform", default=this_platform(),
                    help="Blender platform of the binary (default: this machine's, %s)"
                         % this_platform())
    args = ap.parse_args(argv)
    if args.platform not in PLATFORMS:
        print("build.py: warning: %s is not one of Blender's platforms (%s)"
              % (args.platform, ", ".join(PLATFORMS)), file=sys.stderr)
    path = build(args.out, args.binary, args.platform)
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
