"""Builds the installable extension zip for one platform: `python3 blender_addon/build.py` ->
dist/tessd-<version>-<platform>.zip at the repository's root (e.g. tessd-0.1.0-linux-x64.zip;
`--out DIR` writes it elsewhere). Nothing is written into the source folder blender_addon/.

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
Blender's spelling: linux-x64, linux-arm64, macos-arm64, macos-x64, windows-x64); a binary whose
format is not that platform's (PE for windows-*, ELF for linux-*, Mach-O for macos-*) is
refused. The Windows zip: `--platform windows-x64 --binary <target dir>/x86_64-pc-windows-gnu/
release/tessd.exe` (cross-built with mingw), bundled as `bin/tessd.exe`. Blender's installer extracts with Python's
zipfile, which drops permission bits, so the add-on makes bin/tessd executable before running
it; the zip still records mode 0755 for tools that honour it.

When Blender's own extension tool is at hand (the `bpy` module's
`bl_pkg/cli/blender_ext.py`, what `blender --command extension validate` runs), the zip is
validated with it; `--no-validate` skips that, `--blender-ext PATH` names the tool. It is looked
for (find_blender_ext) in the `bpy` module of the Python running build.py, in the `bpy` of the
repository's .venv, and beside a `blender` on PATH (its bundled scripts folder); when none has
it, the output says where it looked.
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
#: Where the zip goes without --out: dist/ at the repository's root, outside the sources.
DEFAULT_OUT = os.path.join(REPO, "dist")
#: The tool's path below a `bpy` package folder (or a Blender install's `<version>/` folder).
BLENDER_EXT = os.path.join("scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")
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


#: The Rust target a platform's binary is cross-built for on another machine (its release
#: build is then in <target dir>/<triple>/release/).
CROSS_TARGETS = {"windows-x64": "x86_64-pc-windows-gnu", "macos-arm64": "aarch64-apple-darwin",
                 "macos-x64": "x86_64-apple-darwin", "linux-x64": "x86_64-unknown-linux-gnu"}


def default_binary(platform):
    """The release build of this checkout (cargo's target folder: $CARGO_TARGET_DIR when set,
    as cargo itself reads it, else the repository's target/): ``release/tessd`` for this
    machine's platform, ``<triple>/release/tessd[.exe]`` for another (a cross build)."""
    target = os.path.abspath(os.environ.get("CARGO_TARGET_DIR") or os.path.join(REPO, "target"))
    exe = "tessd.exe" if platform.startswith("windows-") else "tessd"
    if platform != this_platform() and platform in CROSS_TARGETS:
        return os.path.join(target, CROSS_TARGETS[platform], "release", exe)
    return os.path.join(target, "release", exe)


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


#: The executable format each platform family runs, by the file's first bytes: PE (``MZ``) on
#: Windows, ELF on Linux, Mach-O (64-bit, either byte order, or universal) on macOS.
FORMATS = {
    "windows": ("a Windows PE executable", (b"MZ",)),
    "linux": ("an ELF executable", (b"\x7fELF",)),
    "macos": ("a Mach-O executable", (b"\xcf\xfa\xed\xfe", b"\xfe\xed\xfa\xcf",
                                      b"\xca\xfe\xba\xbe")),
}


def binary_format(path):
    """The platform family (windows, linux, macos) whose executable format ``path`` has, by its
    first bytes; None for anything else."""
    with open(path, "rb") as f:
        head = f.read(4)
    for family, (_, magics) in FORMATS.items():
        if any(head.startswith(m) for m in magics):
            return family
    return None


def _check_binary(binary, platform):
    if not os.path.isfile(binary):
        raise SystemExit("build.py: the tessd binary %s does not exist; build it with "
                         "`cargo build --release -p tessd` or pass --binary PATH" % binary)
    family = platform.split("-", 1)[0]
    if family in FORMATS:
        found = binary_format(binary)
        if found != family:
            raise SystemExit("build.py: --platform %s needs %s, but the tessd binary %s is %s "
                             "(build it for that platform, e.g. `cargo build --release --target "
                             "x86_64-pc-windows-gnu -p tessd` for windows-x64)"
                             % (platform, FORMATS[family][0], binary,
                                FORMATS[found][0] if found else "none of PE, ELF or Mach-O"))
    if family != "windows" and not os.access(binary, os.X_OK):
        raise SystemExit("build.py: %s is not executable" % binary)


def build(out_dir, binary=None, platform=None):
    """Writes tessd-<version>-<platform>.zip into ``out_dir``; returns its path."""
    platform = platform or this_platform()
    binary = binary or default_binary(platform)
    _check_binary(binary, platform)
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


def blender_ext_places():
    """The glob patterns where Blender's blender_ext.py may be, in the order they are tried:
    the `bpy` module of the running Python (importable, not imported: importing bpy takes
    seconds), the `bpy` of the repository's .venv, then a `blender` on PATH (a Blender install
    keeps its scripts in `<version>/scripts` beside the executable, or below share/blender on
    Linux distributions)."""
    import sysconfig

    # The running Python's site-packages first: once bpy is imported, its scripts' own `bpy`
    # module folder is on sys.path too and would be found before the package.
    places = [os.path.join(sysconfig.get_paths()[key], "bpy", "*", BLENDER_EXT)
              for key in ("purelib", "platlib")]
    try:
        import importlib.machinery

        spec = importlib.machinery.PathFinder.find_spec("bpy")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            places.append(os.path.join(folder, "*", BLENDER_EXT))
    places.append(os.path.join(REPO, ".venv", "lib", "python3*", "site-packages", "bpy", "*",
                               BLENDER_EXT))
    import shutil

    blender = shutil.which("blender")
    if blender:
        real = os.path.dirname(os.path.realpath(blender))
        places.append(os.path.join(real, "*", BLENDER_EXT))
        places.append(os.path.join(os.path.dirname(real), "share", "blender", "*", BLENDER_EXT))
    return list(dict.fromkeys(places))


def find_blender_ext(places=None):
    """The newest blender_ext.py found in :func:`blender_ext_places`, or None."""
    for pattern in blender_ext_places() if places is None else places:
        hits = sorted(glob.glob(pattern))
        if hits:
            return hits[-1]
    return None


def validate(zip_path, tool):
    """Runs Blender's `extension validate` on the zip; returns its exit status."""
    proc = subprocess.run([sys.executable, tool, "validate", zip_path],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    sys.stdout.write(proc.stdout)
    return proc.returncode


def make_parser():
    """The command line's parser."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=DEFAULT_OUT,
                    help="output folder (default: dist/ at the repository's root, %s)" % DEFAULT_OUT)
    ap.add_argument("--no-validate", action="store_true")
    ap.add_argument("--blender-ext", help="path of Blender's bl_pkg/cli/blender_ext.py")
    ap.add_argument("--binary", help="the tessd executable to bundle as bin/tessd (bin/tessd.exe "
                                     "for windows-*; default: release/tessd in $CARGO_TARGET_DIR "
                                     "or this repository's target/)")
    ap.add_argument("--platform", default=this_platform(),
                    help="Blender platform of the binary (default: this machine's, %s)"
                         % this_platform())
    return ap


def main(argv=None):
    args = make_parser().parse_args(argv)
    if args.platform not in PLATFORMS:
        print("build.py: warning: %s is not one of Blender's platforms (%s)"
              % (args.platform, ", ".join(PLATFORMS)), file=sys.stderr)
    path = build(args.out, args.binary, args.platform)
    print(path)
    if not args.no_validate:
        places = blender_ext_places()
        tool = args.blender_ext or find_blender_ext(places)
        if tool is None:
            print("not validated: Blender's blender_ext.py not found; looked in:\n  %s\n"
                  "(pip install bpy into the Python running build.py, put `blender` on PATH, pass "
                  "--blender-ext PATH, or run `blender --command extension validate %s`)"
                  % ("\n  ".join(places), path))
        elif validate(path, tool) != 0:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
