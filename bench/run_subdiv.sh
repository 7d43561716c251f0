#!/usr/bin/env bash
# Subdivision benchmark (side by side, one run): tessd's topology and apply phases on the CPU
# (rayon pools of 1 and 2 threads) and its GPU apply (tessd-gpu; lavapipe on a machine without
# a GPU) vs OpenSubdiv 3.5 (osd_bench: RefineUniform, PrimvarRefiner, stencil tables +
# CpuEvaluator) vs Blender's Subdivision Surface modifier, uniform Catmull-Clark levels 1-5 on
# the same cages: cube (6 quads) and torus_knot_96 (96 quads), the sizes of the paper's first
# two models; quadknot.obj (1440 quads, standing in for its 1292-face model);
# spot_control_mesh.obj; torus_8192 (the reference case).
#
#   bash bench/run_subdiv.sh [extra `bench-subdiv run` options, e.g. --levels 1,2,3]
#
# Writes bench/results/subdiv_raw.jsonl (one line per tool, thread count, cage and level),
# subdiv.md and subdiv_time_per_vertex.png. Needs libosd-dev and g++ (setup_osd.sh installs the
# library when missing), Blender's `bpy` in .venv (scripts/setup.sh) and matplotlib in
# .venv-bench (bench/requirements-bench.txt). Cages go to $BENCH_WORK (default
# /tmp/tessd-bench-subdiv). About 5 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"
BPY="${BLENDER_PYTHON:-$PWD/.venv/bin/python}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-subdiv}"
DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
LEVELS="${LEVELS:-1,2,3,4,5}"
start=$(date +%s)

bash bench/subdiv/setup_osd.sh
cargo build --release -q -p tessd-bench-subdiv
python3 bench/subdiv/make_cages.py "$WORK/cages" >/dev/null
CAGES="$WORK/cages/cube.obj,$WORK/cages/torus_knot_96.obj,$DATA/mesh/spot_control_mesh.obj,$DATA/mesh/quadknot.obj,$WORK/cages/torus_8192.obj"

mkdir -p bench/results
JSONL=bench/results/subdiv_raw.jsonl
rm -f "$JSONL"
target/release/bench-subdiv run --cages "$CAGES" --levels "$LEVELS" --threads 1,2 --tools tessd,gpu,osd \
    --osd bench/out/subdiv/osd_bench --jsonl "$JSONL" --budget 2 --min-repeat 5 --max-repeat 31 \
    --osd-budget 40 --osd-max-repeat 9 "$@"
"$BPY" bench/subdiv/blender_bench.py run --cages "$CAGES" --levels "$LEVELS" --jsonl "$JSONL" \
    --budget 8 --min-repeat 1 --max-repeat 9
"$PY" bench/subdiv/report.py --jsonl "$JSONL" --out bench/results --wall-s "$(( $(date +%s) - start ))"
echo "subdivision benchmark: $(( $(date +%s) - start )) s"
