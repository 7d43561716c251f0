#!/usr/bin/env bash
# Runs every example of examples/ (examples/README.md) as a user would, each with its own
# interpreter, into a temporary folder, and checks what each one wrote: the files are there and
# not empty, USD stages open in usd-core (prims, meshes and faces counted), PNGs have the PNG
# signature. Prints `examples: NAME ok (N s)` per example (after its checks' lines); at the first
# failure it shows the example's output and exits non-zero, naming it.
#
# Assumes scripts/setup.sh has run: .venv (bpy, usd-core), .venv-cad (cadquery), .venv-b123d
# (build123d), FreeCAD's freecadcmd, and the release daemon, target/release/tessd
# ($CARGO_TARGET_DIR honoured; $TESSD_BIN overrides). The Rust example is built here (cargo).
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD

die() { echo "run_examples.sh: $*" >&2; exit 1; }
export TESSD_BIN="${TESSD_BIN:-${CARGO_TARGET_DIR:-$REPO/target}/release/tessd}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$REPO/../shared/data}"
[ -x "$TESSD_BIN" ] || die "no tessd binary at $TESSD_BIN (cargo build --release -p tessd)"
[ -d "$TESSD_SHARED_DATA/mesh" ] || die "no shared data at $TESSD_SHARED_DATA"
for tool in .venv/bin/python .venv-cad/bin/python .venv-b123d/bin/python freecadcmd; do
  command -v "$tool" >/dev/null || die "$tool not found (scripts/setup.sh installs it)"
done

WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessd-examples-XXXXXX")
trap 'rm -rf "$WORK"' EXIT
OUT=$WORK/out
# A private runtime folder: whatever uses the default socket (the FreeCAD workbench) gets a
# daemon of its own there, never the user's.
export XDG_RUNTIME_DIR=$WORK/run
mkdir -m 700 "$XDG_RUNTIME_DIR"

log() { echo "$WORK/${1//\//_}.log"; }  # log NAME: where the example's output goes

fail() {  # fail NAME WHY: shows the end of the example's output, then stops
  [ -f "$(log "$1")" ] && sed 's/^/  | /' "$(log "$1")" | tail -60 >&2
  echo "examples: $1 FAILED: $2" >&2
  exit 1
}

run() {  # run NAME COMMAND...: runs an example, its output into $(log NAME)
  local name=$1 status=0
  shift
  START=$(date +%s%N)
  "$@" >"$(log "$name")" 2>&1 || status=$?
  [ "$status" -eq 0 ] || fail "$name" "exit status $status"
}

ok() {  # ok NAME: the summary line, with the time since `run` started the example
  local ms=$((($(date +%s%N) - START) / 1000000))
  printf 'examples: %s ok (%d.%d s)\n' "$1" $((ms / 1000)) $((ms % 1000 / 100))
}

# check NAME FILE...: every FILE exists and is not empty; .usda stages are opened with usd-core
# (meshes and faces counted, at least one face), .png files start with the PNG signature.
check() {
  local name=$1 f usd=()
  shift
  for f in "$@"; do
    [ -s "$f" ] || fail "$name" "${f#"$OUT"/} is missing or empty"
    case $f in
      *.usda) usd+=("$f") ;;
      *.png)
        [ "$(head -c 8 "$f" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] \
          || fail "$name" "${f#"$OUT"/} is not a PNG"
        echo "  ${f#"$OUT"/}: PNG, $(stat -c %s "$f") bytes" ;;
    esac
  done
  [ ${#usd[@]} -eq 0 ] && return
  if ! .venv/bin/python - "$OUT" "${usd[@]}" >"$WORK/usd.log" 2>&1 <<'EOF'; then
import os, sys
from pxr import Usd, UsdGeom

out = sys.argv[1]
for path in sys.argv[2:]:
    stage = Usd.Stage.Open(path)
    prims = list(stage.Traverse())
    meshes = [UsdGeom.Mesh(p) for p in prims if p.IsA(UsdGeom.Mesh)]
    faces = sum(len(m.GetFaceVertexCountsAttr().Get() or []) for m in meshes)
    variants = sum(len(p.GetVariantSets().GetNames()) for p in prims)
    print("  %s: %d prims, %d meshes, %d faces%s" % (
        os.path.relpath(path, out), len(prims), len(meshes), faces,
        ", %d variant set(s)" % variants if variants else ""))
    assert faces > 0, "%s: no mesh faces" % path
EOF
    cat "$WORK/usd.log" >>"$(log "$name")"
    fail "$name" "a USD stage did not check out"
  fi
  cat "$WORK/usd.log"
}

# 7. The wire protocol by hand (any Python 3, no tessd package).
run client_from_scratch python3 examples/client_from_scratch.py "$OUT/client_from_scratch"
grep -q '"type": "ok"' "$(log client_from_scratch)" || fail client_from_scratch "no ok reply"
check client_from_scratch "$OUT/client_from_scratch/scratch_bunny.ply"
ok client_from_scratch

# 6. The Rust client (its crate is a workspace member; built in release like the daemon).
run rust_client cargo run --quiet --release -p tessd-example-client
grep '^simplify: .* ms in the daemon' "$(log rust_client)" | sed 's/^/  /' \
  || fail rust_client "no simplify line printed"
ok rust_client

# 5. Job files, each run by `tessd job run` from a copy beside a `data` link to the shared data.
mkdir -p "$OUT/jobs"
cp examples/jobs/*.json "$OUT/jobs/"
ln -s "$(cd "$TESSD_SHARED_DATA" && pwd)" "$OUT/jobs/data"
declare -A JOB_OUTPUTS=(
  [mesh_stats]="" [mesh_convert]="spot.usda" [brep_load]=""
  [simplify]="bunny_simplified.ply bunny_cells.obj"
  [lod]="bunny_lods.usda bunny_lods_LOD0.ply bunny_lods_LOD1.ply bunny_lods_LOD2.ply
         bunny_lods_LOD3.ply"
  [subdivide]="spot_subdiv.usda" [compare]="bunny_10pct.ply" [tessellate]="crankarm.usda"
  [render]="crankarm.png bunny_gooch.png"
)
for file in examples/jobs/*.json; do
  job=$(basename "$file" .json)
  [ -n "${JOB_OUTPUTS[$job]+set}" ] || fail "jobs/$job.json" "its outputs are not in JOB_OUTPUTS"
  # The results (JSON lines on stdout) go to <job>.result.json, which is checked too.
  run "jobs/$job.json" sh -c '"$TESSD_BIN" job run "$1" >"${1%.json}.result.json"' sh \
    "$OUT/jobs/$job.json"
  files=("$OUT/jobs/$job.result.json")
  for f in ${JOB_OUTPUTS[$job]}; do files+=("$OUT/jobs/$f"); done
  check "jobs/$job.json" "${files[@]}"
  ok "jobs/$job.json"
done

# 1. cadquery -> export_shape -> tessellate (USD) and render (PNG).
run cadquery_part .venv-cad/bin/python examples/cadquery_part.py "$OUT/cadquery_part"
check cadquery_part "$OUT/cadquery_part/part.usda" "$OUT/cadquery_part/part.png"
ok cadquery_part

# 2. build123d assembly -> tessellation per part + LOD chains, one assembly stage.
dir=$OUT/build123d_assembly
run build123d_assembly .venv-b123d/bin/python examples/build123d_assembly.py "$dir"
check build123d_assembly "$dir"/{plate,bolt,nut,assembly}.usda
ok build123d_assembly

# 3. The Blender add-on's operators, headless (bpy as a module).
dir=$OUT/blender_headless
run blender_headless .venv/bin/python examples/blender_headless.py "$dir"
check blender_headless "$dir/blender_headless.blend" "$dir/bunny_lods.usda"
ok blender_headless

# 4. A FreeCAD macro on the workbench's console API, in freecadcmd, with the workbench linked
# into the Mod folder of a throw-away HOME (as tests/freecad_plugin/run.sh does).
dir=$OUT/freecad_macro
mkdir -p "$WORK/home"
run freecad_macro sh -c 'python3 freecad_plugin/install.py --link --mod-dir "$1" &&
  exec env -u XDG_DATA_HOME -u XDG_CONFIG_HOME -u FREECAD_USER_HOME HOME="$2" \
    freecadcmd examples/freecad_macro.FCMacro "$3"' sh \
  "$WORK/home/.local/share/FreeCAD/Mod" "$WORK/home" "$dir"
check freecad_macro "$dir/freecad_macro.usda" "$dir/freecad_macro.FCStd"
ok freecad_macro

# Nothing left running: every example stops the daemon it started.
ours="serve --socket ($WORK|${TMPDIR:-/tmp}/tessd-(ex|rs|blender)-)"
for _ in $(seq 20); do pgrep -f "$ours" >/dev/null || break; sleep 0.1; done
if pgrep -f "$ours" >/dev/null; then
  pgrep -af "$ours" >&2
  die "an example left its daemon running (above)"
fi
echo "examples: all ok"
