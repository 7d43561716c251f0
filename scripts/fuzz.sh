#!/usr/bin/env bash
# Coverage-guided fuzzing of every decoder (fuzz/, cargo-fuzz + libFuzzer, nightly toolchain).
#
#   bash scripts/fuzz.sh [SECONDS]   build every target once, then run each SECONDS (default 60)
#                                    on its kept corpus fuzz/corpus/<target>/, which is read, never
#                                    written: new inputs go to a fresh temporary folder. Prints per
#                                    target executions/s, coverage (libFuzzer's `cov:` edges),
#                                    corpus size and crashes; exits non-zero when any target
#                                    leaves a crash, timeout (> 1 s; the B-Rep target 10 s and
#                                    the codec 5 s, see below) or out-of-memory (> 2 GB)
#                                    artefact (their paths are printed).
#   bash scripts/fuzz.sh cmin        minimise every kept corpus (`cargo fuzz cmin`), after adding
#                                    what long runs found under $FUZZ_WORK_DIR/<target>/ if set.
#
# Environment: FUZZ_TARGETS="frame codec" runs only those; FUZZ_WORK_DIR=DIR keeps each run's new
# inputs in DIR/<target>/ (instead of a temporary folder) for a later `cmin`; artefacts go to
# ${FUZZ_WORK_DIR:-fuzz}/artifacts/<target>/. CARGO_TARGET_DIR is honoured (the binaries are
# then under $CARGO_TARGET_DIR/x86_64-unknown-linux-gnu/release). FUZZ_DROP_BUILD=1 deletes the
# instrumented build (~1.5 GB) after the runs, as CI does to keep its disk for the later steps.
# Needs the nightly toolchain and
# cargo-fuzz: `bash scripts/setup.sh --fuzz` installs them when missing.
set -euo pipefail
cd "$(dirname "$0")/.."

TRIPLE=x86_64-unknown-linux-gnu
# Release with debug assertions and overflow checks, AddressSanitizer (cargo-fuzz's default),
# which also lets libFuzzer refuse any single allocation over the memory limit.
BUILD_FLAGS=(-O -a --fuzz-dir fuzz)
ALL_TARGETS=(frame envelope mesh_obj mesh_ply mesh_stl mesh_off mesh_stream brep job_file codec
  render_params)
read -r -a TARGETS <<<"${FUZZ_TARGETS:-${ALL_TARGETS[*]}}"
# The dictionary of each target (fuzz/dict/).
declare -A DICT=([frame]=json [envelope]=json [mesh_obj]=obj [mesh_ply]=ply [mesh_stl]=stl
  [mesh_off]=off [mesh_stream]=stream [brep]=brep [job_file]=json [codec]=codec [render_params]=json)
# libFuzzer's flags: 1 s per input, 2 GB of memory. The frame decoder allocates each array of
# a checked table before its bytes arrive (zeroed, so committed only as they are received:
# docs/protocol.md), up to the daemon's 4 GiB payload limit; its single-allocation limit is
# that (the envelope target's too, as it decodes frames first), its resident-memory limit
# stays 2 GB.
# The B-Rep target's tessellation runs 30-80x slower instrumented than in a release build (the
# sanitizer, coverage counters, and spade's own debug checks of its triangulation): a document
# that tessellates in 60 ms takes 2-5 s here, so its limit is 10 s, which is ~0.2 s of release.
# The codec target decodes each input three times (whole, to a precision, one view): a 1 KB file
# whose index claims a cell of ~36 000 symbols with geometry ahead decodes in ~75 ms in release
# and 2.8 s here (coverage counters on every comparison of the star walks), so its limit is 5 s.
COMMON=(-rss_limit_mb=2048 -print_final_stats=1)
declare -A EXTRA=([frame]=-malloc_limit_mb=4100 [envelope]=-malloc_limit_mb=4100
  [brep]=-timeout=10 [codec]=-timeout=5)
# Tessellation runs its faces on rayon: one worker keeps runs reproducible and the cores free.
export RAYON_NUM_THREADS=1

if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
  echo "fuzz: the nightly toolchain or cargo-fuzz is missing; installing (scripts/setup.sh --fuzz)"
  bash scripts/setup.sh --fuzz
fi

build() {
  echo "fuzz: building the targets (cargo +nightly fuzz build ${BUILD_FLAGS[*]})"
  cargo +nightly fuzz build "${BUILD_FLAGS[@]}"
  local dir
  dir=$(cargo metadata --manifest-path fuzz/Cargo.toml --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
  BIN_DIR="$dir/$TRIPLE/release"
  FUZZ_BUILD_DIR="$dir/$TRIPLE"
  local free
  free=$(df -h --output=avail . | tail -1 | tr -d ' ')
  echo "fuzz: build $(du -sh "$FUZZ_BUILD_DIR" | cut -f1), $free free on disk"
}

# Each run's scratch: logs, new inputs without FUZZ_WORK_DIR, and the mesh_stream target's input
# file (it writes to TMPDIR).
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

if [ "${1:-}" = "cmin" ]; then
  for t in "${TARGETS[@]}"; do
    kept="fuzz/corpus/$t"
    if [ -n "${FUZZ_WORK_DIR:-}" ] && [ -d "$FUZZ_WORK_DIR/$t" ]; then
      # Content-named files (libFuzzer names inputs by their SHA-1): copying never clobbers.
      cp -n "$FUZZ_WORK_DIR/$t"/* "$kept"/ 2>/dev/null || true
    fi
    before=$(find "$kept" -type f | wc -l)
    TMPDIR="$TMP" cargo +nightly fuzz cmin "${BUILD_FLAGS[@]}" "$t" "$kept" -- -timeout=1 \
      "${COMMON[@]}" ${EXTRA[$t]:-} >"$TMP/cmin-$t.log" 2>&1 || {
      tail -20 "$TMP/cmin-$t.log"
      echo "fuzz: cmin of $t failed" >&2
      exit 1
    }
    after=$(find "$kept" -type f | wc -l)
    echo "fuzz: $t corpus minimised: $before -> $after inputs, $(du -sh "$kept" | cut -f1)"
  done
  exit 0
fi

SECONDS_EACH=${1:-60}
case $SECONDS_EACH in '' | *[!0-9]*)
  echo "usage: scripts/fuzz.sh [SECONDS] | cmin" >&2
  exit 2
  ;;
esac

build
ART_ROOT="${FUZZ_WORK_DIR:-fuzz}/artifacts"
failed=()
printf '%-14s %8s %10s %8s %8s %10s %s\n' target seconds "execs/s" "cov" "corpus" "peak MB" crashes
for t in "${TARGETS[@]}"; do
  new="${FUZZ_WORK_DIR:-$TMP}/$t"
  art="$ART_ROOT/$t"
  mkdir -p "$new" "$art"
  log="$TMP/$t.log"
  before=$(find "$art" -type f | wc -l)
  start=$(date +%s)
  rc=0
  TMPDIR="$TMP" "$BIN_DIR/$t" -max_total_time="$SECONDS_EACH" -timeout=1 "${COMMON[@]}" \
    ${EXTRA[$t]:-} -dict="fuzz/dict/${DICT[$t]}.dict" -artifact_prefix="$art/" "$new" "fuzz/corpus/$t" \
    >"$log" 2>&1 || rc=$?
  took=$(($(date +%s) - start))
  execs=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  peak=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log" | tail -1)
  cov=$(grep -oE '^#[0-9]+.*cov: [0-9]+' "$log" | tail -1 | sed 's/.*cov: //')
  corpus=$(grep -oE '^#[0-9]+.*corp: [0-9]+/[0-9]+[a-zA-Z]*' "$log" | tail -1 | sed 's/.*corp: //')
  found=$(find "$art" -type f | wc -l)
  crashes=$((found - before))
  printf '%-14s %8s %10s %8s %8s %10s %s\n' "$t" "$took" "${execs:-?}" "${cov:-?}" \
    "${corpus:-?}" "${peak:-?}" "$crashes"
  if [ "$rc" -ne 0 ] || [ "$crashes" -ne 0 ]; then
    failed+=("$t")
    echo "fuzz: $t exited $rc; its log ends:"
    grep -E 'ERROR|panicked|SUMMARY|deadly signal|Test unit written' "$log" | head -20 | sed 's/^/    /'
    find "$art" -type f -newermt "@$start" | sed 's/^/    artefact: /'
    # Keep the log beside the artefacts for whoever reads them later.
    cp "$log" "$ART_ROOT/$t.last-run.log"
  fi
done
if [ "${FUZZ_DROP_BUILD:-0}" = 1 ]; then
  rm -rf "$FUZZ_BUILD_DIR"
fi
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]} (artefacts under $ART_ROOT/; reproduce with"
  echo "      cargo +nightly fuzz run ${BUILD_FLAGS[*]} TARGET ARTEFACT)"
  exit 1
fi
echo "fuzz: ${#TARGETS[@]} targets, ${SECONDS_EACH} s each: no crash, timeout or out-of-memory"
