#!/usr/bin/env bash
# Protocol benchmark (issue 2): socket round trip of a 5 M-triangle mesh beside a raw
# Unix-socket echo of the same bytes, and a 10 M-triangle binary PLY load beside a plain read.
# Writes bench/results/ipc.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p tessd --example bench_ipc
mkdir -p bench/results
{
  echo "# IPC and loader benchmark"
  echo
  echo "Machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%F)."
  echo "Command: \`bash bench/run_ipc.sh\` (\`cargo run --release -p tessd --example bench_ipc -- ${1:-5} ${2:-10}\`)."
  echo
  TESSD_LOG=warn target/release/examples/bench_ipc "${1:-5}" "${2:-10}"
} | tee bench/results/ipc.md
