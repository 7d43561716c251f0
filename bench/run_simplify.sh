#!/usr/bin/env bash
# Simplification benchmark (side by side, one run): tessd grid / quality / complexity
# (barycentre and quadric representatives) vs meshoptimizer simplifySloppy / simplify (the
# `meshopt` crate) vs MeshLab vertex clustering (pymeshlab), on the shared meshes and generated
# bumpy tori up to 10 M triangles, at 50 / 10 / 1 % of the input vertices.
#
#   bash bench/run_simplify.sh [extra `bench-simplify run` options, e.g. --sizes 0.1,1 --scaling-sizes ""]
#
# Writes bench/results/simplify_raw.jsonl (one line per mesh, method, target),
# simplify_inputs.json (the inputs), simplify.md, simplify_summary.json and the plots
# simplify_error_vs_size.png, simplify_time_vs_input.png. Outputs and generated inputs go to
# $BENCH_WORK (default /tmp/tessd-bench-simplify). Needs the bench venv (.venv-bench, see
# bench/requirements-bench.txt) for MeshLab and matplotlib. About 20 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-simplify}"
start=$(date +%s)
cargo build --release -q -p tessd-bench-simplify
mkdir -p bench/results "$WORK"
rm -f bench/results/simplify_raw.jsonl
rm -rf "$WORK/outputs"
target/release/bench-simplify run --work "$WORK" "$@"
"$PY" bench/simplify/meshlab.py run --harness target/release/bench-simplify --work "$WORK"
"$PY" bench/simplify/report.py --wall-s "$(( $(date +%s) - start ))"
echo "simplify benchmark: $(( $(date +%s) - start )) s"
