#!/usr/bin/env bash
# `tessd view` benchmark (issue 35): scripted camera paths in a real window (an Xvfb of its own,
# lavapipe when there is no GPU) through
#   - a B-Rep assembly (5 OpenCASCADE parts of the shared data, --cracks object) at 1280x720 and
#     640x360, and --cracks image at 640x360 (an orbit of 12 frames: lavapipe's object-space
#     filling takes seconds a frame);
#   - a >= 10 M-triangle .tsc (fandisk Loop-subdivided 5 times: 13.3 M triangles), built once
#     into bench/view/work/ (git-ignored; ~50 s), refined while the camera orbits and flies in;
#   - subdivided cages (spot_control_mesh, quadknot) at levels 0-4, --subdivision-device cpu|gpu
#     (paper 002, table 7.2), a 60-frame orbit at 1280x720;
# then bench/results/view.md (median / p95 frame times, fps, triangles, adapter) and the raw
# bench/results/view_raw.json. No build: uses $TESSD_BIN (default target/release/tessd), copied
# first since target/ may be rebuilt during the run. Needs Xvfb (scripts/setup.sh).
#
#   bash bench/run_view.sh [view_bench.py run options, e.g. --paths subdiv --brep-frames 6]
#
# About 5 min on 2 cores with lavapipe (plus ~1 min the first time, for the .tsc).
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-$PWD/.venv/bin/python}"
BIN="${TESSD_BIN:-target/release/tessd}"
WORK="${BENCH_WORK:-$PWD/bench/view/work}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
start=$(date +%s)
mkdir -p "$WORK" bench/results
cp "$BIN" "$WORK/tessd"
binary_note="target/release/tessd of $(stat -c '%y' "$BIN" | cut -d. -f1) UTC, sha1 $(sha1sum "$WORK/tessd" | cut -c1-10)"
RAW=bench/results/view_raw.json
"$PY" bench/view/view_bench.py run --tessd "$WORK/tessd" --work "$WORK" --raw "$RAW" \
    --binary-note "$binary_note" "$@"
"$PY" bench/view/view_bench.py report --raw "$RAW" --out bench/results/view.md
echo "View benchmark: $(( $(date +%s) - start )) s"
