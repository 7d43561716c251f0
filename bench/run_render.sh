#!/usr/bin/env bash
# Render benchmark (paper 001, table 1; issue: render performance), one run: every STEP part of
# $TESSD_SHARED_DATA/brep (exported to tessd-brep JSON as tests/render_reference does) plus the
# bottle (core/tessellate/tests/data/bottle.json), iso view:
#   - tessd render per step (--cracks object|image|none) at 1280x720, median of 3 after one
#     warm-up per mode (the first shader compile on lavapipe is excluded);
#   - the same modes and tessd's full-scene ray caster (--raycast) at 320x240 for the ratios
#     (the ray caster costs ~100 us a pixel on lavapipe: 1280x720 would take minutes a frame);
#   - the reference ray tracer (tests/render_reference/reference.py: BRepMesh 1e-3 + Embree);
#   - trim_bytes vs `tessd tessellate --tolerance 0.01mm` (12 B/vertex + 12 B/triangle);
#   - the bottle at 320x240 ... 1920x1080;
# then bench/results/render.md and render_steps.png. No build: uses $TESSD_BIN (default
# target/release/tessd), copied first since target/ may be rebuilt during the run.
#
#   bash bench/run_render.sh [extra `render_bench.py run` options, e.g. --runs 5 --ray-size 640x480]
#
# About 6-8 min on 2 cores. Raw results: bench/results/render_raw.jsonl (deleted first).
set -euo pipefail
cd "$(dirname "$0")/.."
CAD="${CAD_PYTHON:-$PWD/.venv-cad/bin/python}"
BIN="${TESSD_BIN:-target/release/tessd}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-render}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
start=$(date +%s)
load_start=$(cut -d' ' -f1-3 /proc/loadavg)
rm -rf "$WORK"
mkdir -p "$WORK" bench/results
cp "$BIN" "$WORK/tessd"
binary_note="$(stat -c '%y' "$BIN" | cut -d. -f1), sha1 $(sha1sum "$WORK/tessd" | cut -c1-10)"
JSONL=bench/results/render_raw.jsonl
rm -f "$JSONL"
PYTHONPATH="$PWD/python" "$CAD" bench/render/render_bench.py run --tessd "$WORK/tessd" \
    --work "$WORK" --jsonl "$JSONL" "$@"
"$CAD" bench/render/render_bench.py report --jsonl "$JSONL" --out bench/results \
    --tessd "$BIN" --binary-note "$binary_note" --wall-s "$(( $(date +%s) - start ))" \
    --load-start "$load_start" --load-end "$(cut -d' ' -f1-3 /proc/loadavg)"
echo "Render benchmark: $(( $(date +%s) - start )) s"
