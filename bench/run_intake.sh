#!/usr/bin/env bash
# Mesh intake benchmark (issue 15, point 0): the in-process phases of taking a 4 M-triangle
# mesh in (arrays → validated Mesh, binary PLY → validated Mesh; one thread) and the end to end
# through a real daemon (`elapsed_ms` of `mesh.convert` and of a 2-cells-per-axis grid
# `simplify`, arrays in, RAYON_NUM_THREADS=1). Writes bench/results/intake.md.
# Usage: bash bench/run_intake.sh [TRIANGLES_M] [RUNS] [BASELINE_TESSD_BIN]
set -euo pipefail
cd "$(dirname "$0")/.."
tris="${1:-4}"
runs="${2:-7}"
baseline="${3:-}"
cargo build --release -q -p tessd --example bench_intake
cargo build --release -q -p tessd
mkdir -p bench/results
daemon_table() {
  echo "| op | triangles | elapsed_ms median | best | M triangles/s (median) |"
  echo "|---|---|---|---|---|"
  .venv/bin/python bench/intake_daemon.py "$1" "$tris" "$runs"
}
{
  echo "# Mesh intake benchmark"
  echo
  echo "Machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%F)."
  echo "Command: \`bash bench/run_intake.sh $tris $runs${baseline:+ $baseline}\`"
  echo "(\`target/release/examples/bench_intake $tris $runs\` and \`.venv/bin/python bench/intake_daemon.py target/release/tessd $tris $runs\`)."
  echo
  target/release/examples/bench_intake "$tris" "$runs"
  echo
  echo "## End to end through the daemon: torus arrays in (f32 [V, 3], u32 [T, 3]), RAYON_NUM_THREADS=1, median of $runs"
  echo
  if [ -n "$baseline" ]; then
    echo "Baseline binary \`$baseline\`:"
    echo
    daemon_table "$baseline"
    echo
    echo "This tree's \`target/release/tessd\`:"
    echo
  fi
  daemon_table target/release/tessd
} | tee bench/results/intake.md
