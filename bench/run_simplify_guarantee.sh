#!/usr/bin/env bash
# The quality goal's surface guarantee and its cost, measured (issue: "the quality goal's bound
# must hold on the surface"):
#   1. bench/results/simplify_guarantee.md — every shared mesh and adversarial mesh at 5, 1, 0.5
#      and 0.1 % (core/simplify/examples/surface_guarantee.rs);
#   2. bench/results/simplify_quality_cost.md — quality-mode time before / after the guarantee,
#      interleaved, single thread, when BEFORE names a commit to compare with (default: none).
#
#   bash bench/run_simplify_guarantee.sh [BEFORE_COMMIT]
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"
TARGET="${CARGO_TARGET_DIR:-$PWD/target}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-guarantee}"
mkdir -p bench/results "$WORK"
start=$(date +%s)
{
  echo "# Quality goal: the surface guarantee on shared and adversarial meshes"
  echo
  echo "Command: \`bash bench/run_simplify_guarantee.sh\` (barycentre representative, longest-edge"
  echo "weights; adversarial meshes, in italics, are built by core/simplify/tests/adversarial). Each"
  echo "ratio is to the tolerance; measured = tessd-compare both ways with every vertex, every edge and"
  echo "1 M face samples per direction. ms = the simplification call, all threads."
  echo
  cargo run --release -q -p tessd-simplify --example surface_guarantee -- "$DATA/mesh"
} > bench/results/simplify_guarantee.md
echo "wrote bench/results/simplify_guarantee.md"
if [ -n "${1:-}" ]; then
  cargo build --release -q -p tessd-bench-simplify -p tessd
  git worktree add -f "$WORK/before" "$1" >/dev/null
  (cd "$WORK/before" && CARGO_TARGET_DIR="$WORK/before-target" cargo build --release -q -p tessd-bench-simplify)
  for n in 300000 1000000 3000000; do
    [ -f "$WORK/torus_$n.ply" ] || "$TARGET/release/bench-simplify" gen "$n" "$WORK/torus_$n.ply"
  done
  "$PY" bench/simplify/quality_cost.py --before "$WORK/before-target/release/bench-simplify" \
    --after "$TARGET/release/bench-simplify" --runs 5 \
    --inputs "$DATA/mesh/bun_zipper.ply" "$DATA/mesh/fandisk.obj" "$WORK/torus_300000.ply" \
             "$WORK/torus_1000000.ply" "$WORK/torus_3000000.ply"
  git worktree remove --force "$WORK/before"
fi
echo "guarantee benchmark: $(( $(date +%s) - start )) s"
