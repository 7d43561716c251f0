#!/usr/bin/env bash
# B-Rep benchmark (issue 6; paper 000's tables 1, 3 and 4), one run: every STEP / IGES / .brep
# file of $TESSD_SHARED_DATA/brep plus the cadquery parts of tests/brep/test_brep_export.py
# (and a plate with 540 holes) are exported to tessd-brep JSON (bench/brep/peer_ocp.py export,
# .venv-cad); then, part by part, back to back:
#   - bench-brep (tessd-trim, tessd-tessellate): the trim structure of every face at
#     ε = 0.1 and 0.01 mm (table 1's quadratics, table 3's bytes, table 4's depths and
#     depth-13 failures, k_i, build time per face), the single-thread CPU classification rate,
#     and tessd's tessellation at 0.1 and 0.01 mm (rayon pools of 2 and 1 threads) with a crack
#     check and a centroid-deviation check;
#   - peer_ocp.py mesh: OCP's BRepMesh_IncrementalMesh at the same linear deflections
#     (angular 0.5, parallel and not), its vertex count (36 bytes each, table 3's static
#     tessellation) and the same deviation check;
# and bench/brep/report.py (.venv-bench, matplotlib) writes bench/results/brep.md and the plots.
#
#   bash bench/run_brep.sh [extra `bench-brep run` options, e.g. --eps 0.1 --tols 0.1]
#
# Raw results: bench/results/brep_raw.jsonl (deleted first). Exported JSON and shapes go to
# $BENCH_WORK (default /tmp/tessd-bench-brep). About 6 min on 2 cores (13 under heavy load), most of it the
# 41-m-long hammer.iges at 0.01 mm (each tessellation child is killed after TESS_TIMEOUT s,
# default 90, and reported as such).
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${BENCH_PYTHON:-$PWD/.venv-bench/bin/python}"
CAD="${CAD_PYTHON:-$PWD/.venv-cad/bin/python}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-brep}"
DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
TESS_TIMEOUT="${TESS_TIMEOUT:-90}"
start=$(date +%s)
load_start=$(cut -d' ' -f1-3 /proc/loadavg)

cargo build --release -q -p tessd-bench-brep
# The code measured: the commit, and whether the crates it times had uncommitted changes.
changed=$(git status --porcelain -- core/brep core/trim core/tessellate | wc -l)
source_note="commit $(git rev-parse --short HEAD)$( [ "$changed" -gt 0 ] && echo " plus uncommitted changes to $changed file(s) of core/brep, core/trim, core/tessellate (diff sha1 $(git diff HEAD -- core/brep core/trim core/tessellate | sha1sum | cut -c1-10), kept in \$BENCH_WORK/source.diff)" || echo ", no local changes to core/brep, core/trim, core/tessellate")."
rm -rf "$WORK"
mkdir -p "$WORK"
# Run a private copy: the shared target/ may be rebuilt by other jobs during the run.
cp target/release/bench-brep "$WORK/bench-brep"
git diff HEAD -- core/brep core/trim core/tessellate > "$WORK/source.diff"
PYTHONPATH="$PWD/python" "$CAD" bench/brep/peer_ocp.py export --data "$DATA/brep" --work "$WORK"

mkdir -p bench/results
JSONL=bench/results/brep_raw.jsonl
rm -f "$JSONL"
# One part at a time, tessd then OCP, so that load from other jobs hits both alike.
mapfile -t PARTS < <(python3 -c 'import json,sys; [print(p["name"]) for p in json.load(open(sys.argv[1]))]' "$WORK/parts.json")
for part in "${PARTS[@]}"; do
    "$WORK/bench-brep" run --manifest "$WORK/parts.json" --jsonl "$JSONL" --only "$part" \
        --tess-timeout "$TESS_TIMEOUT" --budget 2 --min-repeat 3 --max-repeat 9 --slow-s 3 "$@"
    PYTHONPATH="$PWD/python" "$CAD" bench/brep/peer_ocp.py mesh --manifest "$WORK/parts.json" \
        --jsonl "$JSONL" --only "$part" --budget 2 --min-repeat 3 --max-repeat 9 --slow-s 3
done
"$PY" bench/brep/report.py --jsonl "$JSONL" --manifest "$WORK/parts.json" --out bench/results \
    --wall-s "$(( $(date +%s) - start ))" --load-start "$load_start" \
    --load-end "$(cut -d' ' -f1-3 /proc/loadavg)" --source-note "$source_note"
echo "B-Rep benchmark: $(( $(date +%s) - start )) s"
