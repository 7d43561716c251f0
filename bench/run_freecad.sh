#!/usr/bin/env bash
# FreeCAD round trip (issue 14): the workbench's Tessellate and Simplify on a ~1 000-face STEP
# assembly beside FreeCAD's own MeshPart.meshFromShape and Mesh.decimate, inside real FreeCAD
# (bench/freecad/roundtrip.py says what is measured). Installs the workbench (linked) into a
# throw-away HOME as tests/freecad_plugin/run.sh does; uses $TESSD_BIN (default the release
# build). Writes bench/results/freecad_roundtrip.json and .md.
#
#   bash bench/run_freecad.sh            # RUNS=5 by default
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
export TESSD_BIN="${TESSD_BIN:-$REPO/target/release/tessd}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$REPO/../shared/data}"
export RUNS="${RUNS:-5}"
export BENCH_OUT="$REPO/bench/results/freecad_roundtrip.json"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessd-freecad-bench-XXXXXX")
trap 'rm -rf "$WORK"' EXIT
export HOME="$WORK/home"
mkdir -p "$HOME"
python3 freecad_plugin/install.py --link --mod-dir "$HOME/.local/share/FreeCAD/Mod" >/dev/null
load_start=$(cut -d' ' -f1-3 /proc/loadavg)
freecadcmd bench/freecad/roundtrip.py 2>&1 | sed -e 's/\t*([0-9]* %)\t*//g' -e 's/Recompute\.*//g' |
  grep -v '^\s*$' | tail -n 60
python3 bench/freecad/report.py "$BENCH_OUT" "$REPO/bench/results/freecad_roundtrip.md" \
  "$load_start" "$(cut -d' ' -f1-3 /proc/loadavg)"
cat "$REPO/bench/results/freecad_roundtrip.md"
