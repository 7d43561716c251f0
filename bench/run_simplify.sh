#!/usr/bin/env bash
# Simplification benchmark (side by side, one run): tessd grid / quality / complexity
# (barycentre and quadric representatives) vs meshoptimizer simplifySloppy / simplify (the
# `meshopt` crate) vs MeshLab vertex clustering (pymeshlab), on the shared meshes and generated
# bumpy tori up to 10 M triangles, at 50 / 10 / 1 % of the input vertices, plus a 50 M-triangle
# torus at 10 %. The tessd methods are also timed with 2 threads (same parameter, output checked
# identical) and, on the tori, end to end through the daemon (`elapsed_ms`, mesh sent as arrays).
#
#   bash bench/run_simplify.sh [extra `bench-simplify run` options, e.g. --sizes 0.1,1 --scaling-sizes ""]
#   SIMPLIFY_BENCH_50M=0 bash bench/run_simplify.sh      # without the 50 M torus
#   bash bench/run_simplify.sh --no-shared --sizes 0.1 --scaling-sizes "" --fractions 0.1   # smoke
#
# Writes bench/results/simplify_raw.jsonl (one line per mesh, method, target; `"record": "e2e"`
# lines for the daemon), simplify_inputs.json (the inputs), simplify_stages.json,
# simplify_headline.json (+ .md), simplify.md, simplify_summary.json
# and the plots simplify_error_vs_size.png, simplify_time_vs_input.png (another folder with
# BENCH_RESULTS=DIR). Outputs and generated inputs go to $BENCH_WORK (default
# /tmp/tessd-bench-simplify; the 50 M torus needs ~1.3 GB there and ~10 GB of RAM). Needs the
# bench venv (.venv-bench, see bench/requirements-bench.txt) for MeshLab, numpy and matplotlib.
#
# Issue 33's stage times and headline (after the harness): `bench-simplify stages` times each
# library stage of every tessd mode (one thread, tori of $SIMPLIFY_STAGES_SIZES M triangles,
# default "1,4", at 10 %) into simplify_stages.json, and `headline.py` the issue's table (a
# $SIMPLIFY_HEADLINE_TRIANGLES-triangle torus, default 4e6: tessd through the daemon vs
# meshoptimizer in process) into simplify_headline.json (+ .md); an empty value skips either.
# The report shows them beside the committed "before" (simplify_stages_before.*,
# simplify_headline_before.*: the library at 65769d72, before issue 33), and issue 33's goal
# rows beside the same rows on the last full run before it (simplify_goals_before.json). To measure "before"
# again in the same run (same machine state), give the binaries built at that commit:
#   SIMPLIFY_BEFORE_HARNESS=/work/target-before/release/bench-simplify \
#   SIMPLIFY_BEFORE_TESSD=/work/target-before/release/tessd bash bench/run_simplify.sh
# (the harness there needs the `stages` subcommand: bench/simplify/src copied over); they
# rewrite $RESULTS/simplify_stages_before.* and simplify_headline_before.* (~3 min more).
#
#   bash bench/run_simplify.sh --quick [more options]   # ~5 min: shared meshes, 0.1 M and 1 M tori at
#                                                        # 10 %, no 50 M torus, stages and headline on 1 M
#
# About 30 min on 2 cores (extrapolated; about 20 without the 50 M torus), plus a few minutes
# for the stage times and the headline.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-simplify}"
RESULTS="${BENCH_RESULTS:-bench/results}"
QUICK=()
STAGES_SIZES="${SIMPLIFY_STAGES_SIZES-1,4}"
HEADLINE_TRIANGLES="${SIMPLIFY_HEADLINE_TRIANGLES-4e6}"
HEADLINE_REPEAT=5
if [[ "${1:-}" == "--quick" ]]; then
    shift
    QUICK=(--sizes 0.1,1 --scaling-sizes "" --fractions 0.1)
    export SIMPLIFY_BENCH_50M=0
    STAGES_SIZES="${SIMPLIFY_STAGES_SIZES-1}"
    HEADLINE_TRIANGLES="${SIMPLIFY_HEADLINE_TRIANGLES-1e6}"
    HEADLINE_REPEAT=3
fi
export SIMPLIFY_BENCH_50M="${SIMPLIFY_BENCH_50M:-1}"
start=$(date +%s)
cargo build --release -q -p tessd -p tessd-bench-simplify
mkdir -p "$RESULTS" "$WORK"
rm -f "$RESULTS/simplify_raw.jsonl"
rm -rf "$WORK/outputs"
FILES=(--jsonl "$RESULTS/simplify_raw.jsonl" --manifest "$RESULTS/simplify_inputs.json")
target/release/bench-simplify run --work "$WORK" "${FILES[@]}" "${QUICK[@]}" "$@"
"$PY" bench/simplify/meshlab.py run --harness target/release/bench-simplify --work "$WORK" "${FILES[@]}"
"$PY" bench/simplify/e2e_daemon.py run --harness target/release/bench-simplify \
    --tessd target/release/tessd --work "$WORK" "${FILES[@]}"
rm -f "$RESULTS/simplify_stages.json" "$RESULTS/simplify_headline.json" "$RESULTS/simplify_headline.md"
if [[ -n "$STAGES_SIZES" ]]; then
    target/release/bench-simplify stages --sizes "$STAGES_SIZES" --fraction 0.1 --repeat 3 \
        --label "after: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- core || echo ' + changes')" \
        --out "$RESULTS/simplify_stages.json"
fi
if [[ -n "$HEADLINE_TRIANGLES" ]]; then
    "$PY" bench/simplify/headline.py run --tessd target/release/tessd --harness target/release/bench-simplify \
        --work "$WORK" --triangles "$HEADLINE_TRIANGLES" --repeat "$HEADLINE_REPEAT" --label after \
        --out "$RESULTS/simplify_headline.json"
fi
BEFORE=()
if [[ -n "${SIMPLIFY_BEFORE_HARNESS:-}" && -n "$STAGES_SIZES" ]]; then
    "$SIMPLIFY_BEFORE_HARNESS" stages --sizes "$STAGES_SIZES" --fraction 0.1 --repeat 3 \
        --label "before: $SIMPLIFY_BEFORE_HARNESS" --out "$RESULTS/simplify_stages_before.json"
    "$PY" bench/simplify/tables.py --stages "$RESULTS/simplify_stages_before.json" \
        --out "$RESULTS/simplify_stages_before.md" --title "Simplification stage times before issue 33"
    BEFORE+=(--before-stages "$RESULTS/simplify_stages_before.json")
fi
if [[ -n "${SIMPLIFY_BEFORE_TESSD:-}" && -n "$HEADLINE_TRIANGLES" ]]; then
    "$PY" bench/simplify/headline.py run --tessd "$SIMPLIFY_BEFORE_TESSD" --harness target/release/bench-simplify \
        --work "$WORK" --triangles "$HEADLINE_TRIANGLES" --repeat "$HEADLINE_REPEAT" --label before \
        --out "$RESULTS/simplify_headline_before.json"
    BEFORE+=(--before-headline "$RESULTS/simplify_headline_before.json")
fi
"$PY" bench/simplify/report.py --wall-s "$(( $(date +%s) - start ))" "${FILES[@]}" --out "$RESULTS" "${BEFORE[@]}"
echo "simplify benchmark: $(( $(date +%s) - start )) s"
