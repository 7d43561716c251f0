#!/usr/bin/env bash
# Codec benchmark (paper 003's Table 2, side by side, one run): `tessd compress` / `tessd
# decompress` (core/codec: Gandoin–Devillers kd-tree coder in an nSP-tree, lossless at p bits)
# vs Draco (DracoPy, compression levels 10 and 7) vs meshoptimizer's vertex + index codecs (the
# `meshopt` wheel; raw, + zstd, + deflate), on every mesh of $TESSD_SHARED_DATA/mesh at p = 12
# and 16 bits per coordinate, all on the same quantised mesh (cubic bbox, step = side/(2^p - 1)),
# with a lossless check of every decoder's output; plus the rate–distortion curves of the bunny
# (`tessd decompress --max-bits B`, B = 4..12, against Draco at 4..16 quantisation bits); and
# issue 34's goal rows (bench/codec/goals.py: every goal reported even where missed, the bunny's
# bit budget before (v1, bench/results/codec_budget_before.json) and now, one-core speed on a
# 1.1 M-triangle torus).
#
#   bash bench/run_codec.sh [extra `run_codec.py run` options, e.g. --meshes stanford_bunny --bits 12]
#   TESSD_BIN=/path/to/tessd bash bench/run_codec.sh      # another binary (then nothing is built)
#
# Writes bench/results/codec_raw.jsonl (one line per mesh, p and codec variant; "record": "rd"
# lines for the rate–distortion points), codec.md, codec_rd.csv and codec_rd.png (another folder
# with BENCH_RESULTS=DIR). .tsc and decoded .ply files go to $BENCH_WORK (default
# /tmp/tessd-bench-codec). Needs the bench venv (.venv-bench, bench/requirements-bench.txt:
# DracoPy, meshopt, zstandard, scipy, matplotlib), which this script creates or updates the way
# scripts/setup.sh does when its requirements changed. Peers alone take about 2 min on 2 cores,
# the rate–distortion distances about 1 min more.
set -euo pipefail
cd "$(dirname "$0")/.."
WORK="${BENCH_WORK:-/tmp/tessd-bench-codec}"
RESULTS="${BENCH_RESULTS:-bench/results}"
DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
start=$(date +%s)

# The bench venv, as scripts/setup.sh's make_venv makes it (rebuilt when the requirements change).
if [ -z "${BENCH_PYTHON:-}" ]; then
    VENV=.venv-bench REQS=bench/requirements-bench.txt
    SYS_PY=${PYTHON:-python3.11}
    command -v "$SYS_PY" >/dev/null || SYS_PY=python3
    [ -x "$VENV/bin/python" ] || { echo "run_codec: creating $VENV"; "$SYS_PY" -m venv "$VENV"; }
    if ! cmp -s "$REQS" "$VENV/.requirements-installed" 2>/dev/null; then
        echo "run_codec: installing $REQS into $VENV"
        "$VENV/bin/python" -m pip install -q --upgrade pip
        "$VENV/bin/python" -m pip install -q -r "$REQS"
        cp "$REQS" "$VENV/.requirements-installed"
    fi
fi
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"

if [ -z "${TESSD_BIN:-}" ]; then
    cargo build --release -q -p tessd
    TESSD_BIN=target/release/tessd
fi
# the one-core speed rows' ~1.1 M-triangle torus (bench/codec/goals.py), generated if missing
if [ ! -f "$WORK/torus1m.ply" ] && [ -z "${CODEC_SPEED_MESH:-}" ]; then
    cargo build --release -q -p tessd-bench-simplify
fi
[ -x "$TESSD_BIN" ] || { echo "run_codec: tessd binary not built yet: $TESSD_BIN" >&2; exit 1; }
mkdir -p "$RESULTS" "$WORK"
# Run a private copy: the shared target/ may be rebuilt by other jobs during the run.
cp "$TESSD_BIN" "$WORK/tessd"
export TESSD_BIN="$WORK/tessd"
rm -f "$RESULTS/codec_raw.jsonl"
"$PY" bench/codec/run_codec.py run --data "$DATA" --work "$WORK" --jsonl "$RESULTS/codec_raw.jsonl" \
    --out "$RESULTS" --command "bash bench/run_codec.sh $*" "$@"
# View-dependent refinement along a camera path through the daemon (paper 003 §6.2, Figure 9).
{
    echo "# View-dependent refinement along a camera path (\`bench/codec/view_path.py\`)"
    echo
    echo "Run $(date -u '+%Y-%m-%d %H:%M UTC'), \`bash bench/run_codec.sh\`. Zoom in from 20 radii to 1.2, half an orbit, zoom out;"
    echo "60 frames, 1280x720, 30° vertical, 1 pixel; one daemon keeps the decoder states between frames;"
    echo "compressed with \`--min-cell 8000\` (several nSP-cells: at the default the bunny and fandisk are one cell)."
    echo
    for m in bun_zipper.ply fandisk.obj; do
        "$PY" bench/codec/view_path.py "$TESSD_BIN" "$DATA/mesh/$m" --frames 60 --jsonl "$WORK/view_$m.jsonl"
        echo
    done
} > "$RESULTS/codec_view.md"
echo "codec benchmark: $(( $(date +%s) - start )) s"
