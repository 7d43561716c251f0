#!/usr/bin/env bash
# Out-of-core codec run (paper 003 Table 1's columns): a generated bumpy torus of N triangles
# (binary PLY, `bench-simplify gen`), `tessd compress` streaming it, then `tessd decompress` back
# to a binary PLY, each under GNU time for the peak resident set; prints one Markdown table row
# and appends the JSON of both runs to bench/results/codec_ooc.jsonl.
#
#   bash bench/codec/run_ooc.sh [--compress-only] [TRIANGLES=200100000] [BITS=16]
#
# TESSD_BIN=path runs that binary instead of building and running target/release/tessd (a
# build made from a known commit while others edit the tree).
#
# --compress-only skips the decompression (30 min at 200 M triangles): the row's decompress
# columns are then empty ("–") and the JSON has no decompress fields.
#
# Needs about 20 GB of free disk in $BENCH_WORK (default /tmp/tessd-bench-ooc) at 200 M
# triangles: the input PLY (3.8 GB), the raw index file and the deflated symbols (temporary),
# and the decoded PLY (3.8 GB).
set -euo pipefail
cd "$(dirname "$0")/../.."
COMPRESS_ONLY=0
if [ "${1:-}" = "--compress-only" ]; then COMPRESS_ONLY=1; shift; fi
TRIS="${1:-200100000}"
BITS="${2:-16}"
WORK="${BENCH_WORK:-/tmp/tessd-bench-ooc}"
mkdir -p "$WORK" bench/results
BIN="${TESSD_BIN:-target/release/tessd}"
if [ -z "${TESSD_BIN:-}" ]; then
    cargo build --release -q -p tessd -p tessd-bench-simplify
fi
IN="$WORK/torus_${TRIS}.ply"
[ -f "$IN" ] || cargo build --release -q -p tessd-bench-simplify
[ -f "$IN" ] || target/release/bench-simplify gen "$TRIS" "$IN"
T=/usr/bin/time
$T -f '%e %M %U %S' -o "$WORK/c.time" "$BIN" compress "$IN" "$WORK/t.tsc" --bits "$BITS" --json > "$WORK/c.json"
rm -f "$WORK/out.ply" "$WORK/d.json" "$WORK/d.time"
if [ "$COMPRESS_ONLY" = 0 ]; then
    $T -f '%e %M' -o "$WORK/d.time" "$BIN" decompress "$WORK/t.tsc" "$WORK/out.ply" --json > "$WORK/d.json"
fi
python3 - "$WORK" "$TRIS" "$BITS" <<'PY'
import json, sys, os, platform
work, tris, bits = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
c = json.load(open(os.path.join(work, "c.json")))
# wall, peak KiB, user and system CPU seconds (both cores: user + system over wall is how busy
# they were)
ce, cm, cu, cs = open(os.path.join(work, "c.time")).read().split()
decoded = os.path.exists(os.path.join(work, "d.json"))
if decoded:
    d = json.load(open(os.path.join(work, "d.json")))
    de, dm = open(os.path.join(work, "d.time")).read().split()
cores = os.cpu_count()
row = dict(triangles=c["input_triangles"], vertices=c["input_vertices"], bits=bits,
           tsc_bytes=c["bytes"], bits_per_vertex=c["bits_per_vertex"], nsp_cells=c["nsp_cells"],
           compress_s=float(ce), compress_peak_mib=int(cm) / 1024, steps_ms=c["steps_ms"], cores=cores,
           compress_user_s=float(cu), compress_sys_s=float(cs),
           raw_bytes=int((3 * bits * c["input_vertices"] + 3 * c["input_triangles"] * __import__("math").log2(max(2, c["input_vertices"]))) / 8))
if decoded:
    row.update(decompress_s=float(de), decompress_peak_mib=int(dm) / 1024,
               decoded_vertices=d["vertices"], decoded_triangles=d["triangles"])
with open("bench/results/codec_ooc.jsonl", "a") as f:
    f.write(json.dumps(row) + "\n")
print("| triangles | p | raw bytes | .tsc bytes | ratio | nSP-cells | compress s (partition / codes / final) | peak MiB | M tri/s per core | decompress s | peak MiB | M tri/s per core |")
print("|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|")
s = c["steps_ms"]
dec = ("%.0f | %.0f | %.3f" % (row["decompress_s"], row["decompress_peak_mib"],
                              row["triangles"] / row["decompress_s"] / cores / 1e6)) if decoded else "– | – | –"
print("| %d | %d | %d | %d | %.2f | %d | %.0f (%.0f / %.0f / %.0f) | %.0f | %.3f | %s |" % (
    row["triangles"], bits, row["raw_bytes"], row["tsc_bytes"], row["raw_bytes"] / row["tsc_bytes"],
    row["nsp_cells"], row["compress_s"], s.get("partition", 0) / 1e3, s.get("codes", 0) / 1e3,
    s.get("final", 0) / 1e3, row["compress_peak_mib"], row["triangles"] / row["compress_s"] / cores / 1e6, dec))
print("compress CPU: user %.0f s + system %.0f s over %.0f s wall = %.2f cores busy" % (
    row["compress_user_s"], row["compress_sys_s"], row["compress_s"],
    (row["compress_user_s"] + row["compress_sys_s"]) / row["compress_s"]))
if decoded:
    print("decoded: %d vertices, %d triangles (input %d, %d)" % (d["vertices"], d["triangles"], c["input_vertices"], c["input_triangles"]))
PY
