#!/usr/bin/env bash
# Checks the one-step install (docs/install.md): builds the tessd wheel from python/ the way
# `pip install ./python` does (pip runs the maturin backend of python/pyproject.toml, which runs
# cargo: the release build of core/tessd, reusing what `cargo build --release -p tessd` left in
# $CARGO_TARGET_DIR or target/), installs it into a fresh venv with cadquery (pinned as in
# python/requirements-cad.txt), and from a folder outside the repository, with no PYTHONPATH and
# no TESSD_BIN, checks that
#   (a) `import tessd` is the venv's copy, not the repository's;
#   (b) tessd.daemon.find_binary() is the binary the wheel put in the venv's bin/ (the venv is
#       not activated: its bin/ is not on PATH);
#   (c) the venv's `tessd --version` runs and reports the package's version;
#   (d) a cadquery part goes through the daemon: examples/cadquery_part.py when the repository
#       has it, else an inline check (a filleted box exported with tessd.brep.export_shape,
#       tessellated to a .usda by a daemon that tessd.ensure_daemon starts on a private socket).
# Every daemon it started is stopped and its temporary folder removed, whatever happens.
#
# Usage: bash scripts/wheel_check.sh [--no-cad]   (--no-cad: skips cadquery and check (d))
# Environment: PYTHON (default python3.11, else python3), CARGO_TARGET_DIR (as cargo reads it),
# KEEP_WHEEL_CHECK=1 keeps the temporary folder for a look.
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null || PY=python3
CAD=1
[ "${1:-}" = "--no-cad" ] && CAD=0

say() { echo "wheel_check: $*"; }
fail() { echo "wheel_check: FAILED: $*" >&2; exit 1; }
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessd-wheel.XXXXXX")
VENV="$WORK/venv"
OUTSIDE="$WORK/outside"      # the checks' working folder: nothing of the repository is there
RUNDIR="$WORK/run"           # XDG_RUNTIME_DIR of the checks: any default socket lands here
TMPBOX="$WORK/tmp"           # TMPDIR of the checks: their temporary sockets land here too
mkdir -p "$OUTSIDE" "$RUNDIR" "$TMPBOX" "$WORK/dist"

# Stops every daemon on a socket under $WORK (politely, with the installed client's
# stop_daemon), then any process still running from $WORK (matched by that unique path, by pid),
# and removes $WORK.
cleanup() {
  local rc=$? sock pid
  set +e
  if [ -x "$VENV/bin/python" ]; then
    for sock in "$WORK"/*.sock "$RUNDIR"/*.sock "$TMPBOX"/*/*.sock; do
      [ -S "$sock" ] || continue
      env -u PYTHONPATH "$VENV/bin/python" -c \
        'import sys, tessd; sys.exit(0 if tessd.stop_daemon(sys.argv[1], timeout=10) else 1)' \
        "$sock" >/dev/null 2>&1 \
        && say "stopped the daemon on $sock"
    done
  fi
  local cmd
  for pid in $(grep -lsF "$WORK/" /proc/[0-9]*/cmdline | cut -d/ -f3); do
    [ "$pid" = "$$" ] && continue
    cmd=$(tr '\0' ' ' 2>/dev/null <"/proc/$pid/cmdline") || continue
    kill "$pid" 2>/dev/null && say "killed leftover process $pid ($cmd)"
  done
  if [ "${KEEP_WHEEL_CHECK:-0}" = 1 ]; then
    say "kept $WORK"
  else
    local t; t=$(now)
    rm -rf "$WORK"
    say "removed $WORK in $(secs "$t" "$(now)") s"
  fi
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

START=$(now)
say "python $("$PY" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])') ($PY), cargo target folder ${CARGO_TARGET_DIR:-$REPO/target}"
"$PY" -m venv "$VENV"
VPY="$VENV/bin/python"

# The wheel, built by pip through the build backend (as `pip install ./python` builds it).
T=$(now)
if ! "$VPY" -m pip wheel -v --no-deps --wheel-dir "$WORK/dist" "$REPO/python" >"$WORK/build.log" 2>&1; then
  tail -n 40 "$WORK/build.log" >&2
  fail "pip wheel ./python"
fi
WHEEL=$(ls "$WORK"/dist/tessd-*.whl)
[ "$(echo "$WHEEL" | wc -l)" = 1 ] || fail "expected one wheel, got: $WHEEL"
say "built $(basename "$WHEEL") in $(secs "$T" "$(now)") s: $(du -k "$WHEEL" | cut -f1) KiB ($(stat -c %s "$WHEEL") bytes)"
say "  cargo compiled $(grep -c ' Compiling ' "$WORK/build.log" || true) crates:$(grep -m1 ' Finished ' "$WORK/build.log" | sed 's/^ *Finished//')"
"$VPY" - "$WHEEL" <<'EOF' || fail "the wheel's contents"
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
need = ["tessd/__init__.py", "tessd/daemon.py", "tessd/brep/__init__.py"]
missing = [n for n in need if n not in names]
binary = [n for n in names if n.endswith(".data/scripts/tessd") or n.endswith(".data/scripts/tessd.exe")]
stray = [n for n in names if "__pycache__" in n or n.endswith(".pyc")]
assert not missing, "missing from the wheel: %s" % missing
assert binary, "no tessd binary under <name>.data/scripts/ in the wheel"
assert not stray, "bytecode in the wheel: %s" % stray[:5]
print("wheel_check: the wheel holds %d files: the client package and %s" % (len(names), binary[0]))
EOF

# The install: the wheel, plus cadquery as pinned for the CAD venv.
T=$(now)
PKGS=("$WHEEL")
if [ $CAD = 1 ]; then
  mapfile -t CAD_PINS < <(grep -E '^(cadquery|cadquery-ocp)==' "$REPO/python/requirements-cad.txt")
  [ ${#CAD_PINS[@]} = 2 ] || fail "cadquery / cadquery-ocp pins not found in python/requirements-cad.txt"
  PKGS+=("${CAD_PINS[@]}")
fi
if ! "$VPY" -m pip install "${PKGS[@]}" >"$WORK/install.log" 2>&1; then
  tail -n 40 "$WORK/install.log" >&2
  fail "pip install ${PKGS[*]}"
fi
say "installed ${PKGS[*]##*/} into a fresh venv in $(secs "$T" "$(now)") s"

# The checks: from outside the repository, no PYTHONPATH, no TESSD_BIN, the venv not activated
# (PATH as the caller has it, without the venv's bin/).
run() {
  (cd "$OUTSIDE" && env -u PYTHONPATH -u TESSD_BIN -u VIRTUAL_ENV XDG_RUNTIME_DIR="$RUNDIR" \
    TMPDIR="$TMPBOX" "$@")
}

run "$VPY" - "$REPO" "$VENV" <<'EOF' || fail "checks (a) and (b)"
import os, sys, sysconfig
repo, venv = (os.path.realpath(p) for p in sys.argv[1:3])
import tessd, tessd.daemon
where = os.path.realpath(tessd.__file__)
site_dirs = {os.path.realpath(sysconfig.get_path(k)) for k in ("purelib", "platlib")}
assert not where.startswith(repo + os.sep), "tessd imported from the repository: %s" % where
assert any(where.startswith(d + os.sep) for d in site_dirs), \
    "tessd is not in the venv's site-packages %s: %s" % (sorted(site_dirs), where)
print("wheel_check: (a) import tessd -> %s" % tessd.__file__)
found = tessd.daemon.find_binary()
bundled = os.path.join(venv, "bin", "tessd")
assert os.path.realpath(found) == os.path.realpath(bundled), \
    "find_binary() is %s, not the venv's %s" % (found, bundled)
on_path = [d for d in os.environ.get("PATH", "").split(os.pathsep) if d and os.path.realpath(d) == os.path.join(venv, "bin")]
assert not on_path, "the venv's bin/ is on PATH: the check would prove nothing"
print("wheel_check: (b) find_binary() -> %s (the venv's bin/ is not on PATH)" % found)
EOF

VERSION=$(run "$VENV/bin/tessd" --version) || fail "(c) $VENV/bin/tessd --version"
PKG_VERSION=$(run "$VPY" -c 'import tessd; print(tessd.__version__)')
[ "$VERSION" = "tessd $PKG_VERSION" ] || fail "(c) tessd --version printed '$VERSION', the package is $PKG_VERSION"
say "(c) $VENV/bin/tessd --version -> $VERSION"

if [ $CAD = 0 ]; then
  say "(d) skipped (--no-cad)"
elif [ -f "$REPO/examples/cadquery_part.py" ]; then
  T=$(now)
  if ! run "$VPY" "$REPO/examples/cadquery_part.py" "$WORK/example-out" >"$WORK/example.log" 2>&1; then
    tail -n 40 "$WORK/example.log" >&2
    fail "(d) examples/cadquery_part.py"
  fi
  sed 's/^/wheel_check:     /' "$WORK/example.log" | tail -n 15
  for f in part.usda part.png; do
    [ -s "$WORK/example-out/$f" ] || fail "(d) examples/cadquery_part.py wrote no $f"
  done
  say "(d) examples/cadquery_part.py ran in $(secs "$T" "$(now)") s: part.usda $(stat -c %s "$WORK/example-out/part.usda") bytes, part.png $(stat -c %s "$WORK/example-out/part.png") bytes"
else
  T=$(now)
  run "$VPY" - "$WORK" <<'EOF' || fail "(d) the inline cadquery check"
import json, os, sys
import cadquery as cq
import tessd
from tessd.brep import export_shape
work = sys.argv[1]
part = cq.Workplane().box(10, 20, 5).fillet(1)
doc = export_shape(part.val().wrapped, units="mm", source="wheel_check box")
with open(os.path.join(work, "box.json"), "w") as f:
    json.dump(doc, f)
sock = tessd.ensure_daemon(socket=os.path.join(work, "d.sock"), timeout=30)
try:
    out = os.path.join(work, "box.usda")
    with tessd.Client(sock, timeout=60) as c:
        result, _ = c.call("tessellate", {"input": os.path.join(work, "box.json"),
                                          "tolerance": "0.05mm", "output": out})
    assert os.path.isfile(out) and os.path.getsize(out) > 0, "no .usda written"
    with open(out) as f:
        head = f.read(5)
    assert head == "#usda", "not a .usda: %r" % head
    print("wheel_check: (d) cadquery box (%d faces) -> %s: %s triangles, %d bytes"
          % (len(doc["faces"]), os.path.basename(out), result.get("triangles"), os.path.getsize(out)))
finally:
    assert tessd.stop_daemon(sock), "the daemon was not running at the end"
EOF
  say "(d) inline cadquery check ran in $(secs "$T" "$(now)") s (examples/cadquery_part.py not in the repository)"
fi

say "passed in $(secs "$START" "$(now)") s"
