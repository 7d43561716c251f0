#!/usr/bin/env bash
# tessd.batch single-node throughput (issue 16, point 4): 1 and 2 Dask workers, LOD chains of
# the shared meshes and tessellation of the shared CAD parts, median of 3 runs each into a fresh
# OUTDIR. Writes bench/results/batch.md (the measured base of docs/scale-out.md). A few minutes
# at most on 2 cores. Needs the CAD venv (dask[distributed] + OCP: python/requirements-cad.txt)
# and the release binary.
set -euo pipefail
cd "$(dirname "$0")/../.."
export TESSD_BIN="${TESSD_BIN:-${CARGO_TARGET_DIR:-$PWD/target}/release/tessd}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
[ -x "$TESSD_BIN" ] || cargo build --release -q -p tessd
PY=${PYTHON:-.venv-cad/bin/python}
"$PY" bench/batch/bench_batch.py "$@"
