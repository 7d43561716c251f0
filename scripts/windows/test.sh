#!/usr/bin/env bash
# The Windows step of scripts/test.sh (issue 37): cross-builds the workspace's tests for
# x86_64-pc-windows-gnu (release, mingw), runs every one of them under Wine through cargo's runner
# (scripts/windows/wine-run.sh: a private Wine prefix with the test-only shim DLL), then the
# checks of what ships for Windows (tests/windows: the add-on zip with tessd.exe, the wheel).
# Prints the counts at the end: test binaries, tests run, passed, failed, ignored, and the tests
# compiled out on Windows (each marked `// windows: compiled out — <reason>` in the code).
# Exits non-zero on any failure.
#
# Extra arguments go to both cargo commands (e.g. `--exclude tessd-ipc` while measuring).
# WINDOWS_DROP_BUILD=1 deletes the Windows build (<target dir>/x86_64-pc-windows-gnu) and the
# Wine prefix (~0.7 GB: Wine 8 copies its DLLs into it) afterwards, as CI does for its disk.
#
# Wine's fidelity for the GPU tests: Wine 8 implements Vulkan (winevulkan over the host's
# libvulkan: lavapipe here) only through its X11 driver, so the run has an X display: Xvfb
# (xvfb-run) when DISPLAY is unset. Wine's DX12 (d3d12 over vkd3d, libvkd3d1) lists a GPU
# adapter but cannot open a device: wgpu's internal HLSL shaders fail in Wine's D3DCompile
# (vkd3d-shader error -5, "Parent device is lost"). The run keeps both backends on purpose:
# tessd_gpu::GpuContext::open passes over an adapter that refuses its device, so the GPU tests
# here also show that fallback (DX12's GPU refused, Vulkan's llvmpipe taken). DX12 itself is
# built and type-checked, not run.
set -euo pipefail
cd "$(dirname "$0")/../.."
TRIPLE=x86_64-pc-windows-gnu
if [ -z "${DISPLAY:-}" ]; then
  command -v xvfb-run >/dev/null || {
    echo "windows: xvfb-run is missing (apt package xvfb; scripts/setup.sh installs it):" \
      "Wine's Vulkan needs an X display" >&2
    exit 1
  }
  exec xvfb-run -a -s "-screen 0 640x480x24 -nolisten tcp" bash "$0" "$@"
fi
export CC_x86_64_pc_windows_gnu=${CC_x86_64_pc_windows_gnu:-x86_64-w64-mingw32-gcc}
export CXX_x86_64_pc_windows_gnu=${CXX_x86_64_pc_windows_gnu:-x86_64-w64-mingw32-g++}
export AR_x86_64_pc_windows_gnu=${AR_x86_64_pc_windows_gnu:-x86_64-w64-mingw32-ar}
TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target}
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT

t0=$SECONDS
cargo test --release --target "$TRIPLE" --workspace --no-run --quiet "$@"
echo "windows: build $((SECONDS - t0)) s"

# One wineserver for the whole run (-p: persistent), so that no test binary starts while the
# previous one's server is exiting (Wine ends its server 3 s after its last program).
# The prefix is made first (wine-run.sh waits for wineboot's server to end, which a persistent
# one never does), and its server has ended (-p refuses to start beside a running one).
export TESSD_WINEPREFIX=${TESSD_WINEPREFIX:-$TARGET_DIR/wine-prefix}
prefix=$TESSD_WINEPREFIX
WINESERVER=$(command -v wineserver || echo /usr/lib/wine/wineserver)
bash scripts/windows/wine-run.sh cmd /c exit 0
WINEPREFIX=$prefix "$WINESERVER" -w
WINEPREFIX=$prefix "$WINESERVER" -p
# Wine's own services (services.exe, winedevice.exe, ...) start with the first program and live
# as long as the server: started here, they hold /dev/null, not the pipe to tee below (which
# would then never end).
bash scripts/windows/wine-run.sh cmd /c exit 0 >/dev/null 2>&1 </dev/null

t1=$SECONDS
status=0
cargo test --release --target "$TRIPLE" --workspace --no-fail-fast "$@" 2>&1 | tee "$LOG" ||
  status=$?
echo "windows: Rust tests under Wine $((SECONDS - t1)) s"

exe=$TARGET_DIR/$TRIPLE/release/tessd.exe
pytest_status=0
if [ -d tests/windows ]; then
  t2=$SECONDS
  TESSD_WINDOWS_EXE=$exe .venv/bin/python -m pytest tests/windows -q -p no:cacheprovider ||
    pytest_status=$?
  echo "windows: pytest tests/windows $((SECONDS - t2)) s"
fi

# End this prefix's persistent wineserver (and the Wine desktop on this X display) before
# xvfb-run stops the display.
WINEPREFIX=$prefix timeout 60 "$WINESERVER" -k 2>/dev/null || true
WINEPREFIX=$prefix timeout 60 "$WINESERVER" -w 2>/dev/null || true
if [ "${WINDOWS_DROP_BUILD:-0}" = 1 ]; then
  rm -rf "${TARGET_DIR:?}/$TRIPLE" "$prefix"
fi

# The counts, from libtest's summaries ("test result: ok. 5 passed; 0 failed; 2 ignored; ...").
binaries=$(grep -cE '^ +Running ' "$LOG" || true)
doctests=$(grep -cE '^ +Doc-tests ' "$LOG" || true)
read -r passed failed ignored < <(grep -E '^test result: ' "$LOG" | awk '
  { for (i = 1; i <= NF; i++) {
      if ($(i + 1) ~ /^passed;?$/) p += $i
      if ($(i + 1) ~ /^failed;?$/) f += $i
      if ($(i + 1) ~ /^ignored;?$/) g += $i } }
  END { print p + 0, f + 0, g + 0 }')
echo "== Windows (x86_64-pc-windows-gnu under Wine) summary"
echo "windows: test binaries: $binaries (+ $doctests doc-test runs)"
echo "windows: tests run: $((passed + failed)), passed: $passed, failed: $failed," \
  "ignored: $ignored"
# Each item compiled out on Windows carries the marker in the comment above its cfg; the reason
# is the rest of that comment, continuation lines included.
out=$(grep -rl --include='*.rs' 'windows: compiled out' core bench examples | sort |
  xargs -r awk '
    function flush() { if (at != "") print "  " at ": " reason; at = "" }
    /windows: compiled out/ {
      flush(); at = FILENAME ":" FNR; reason = $0
      sub(/.*windows: compiled out *(—|-)* */, "", reason); next }
    at != "" && /^[ \t]*\/\// { line = $0; sub(/^[ \t]*\/\/+ */, "", line)
      reason = reason " " line; next }
    { flush() }
    END { flush() }')
echo "windows: compiled out on Windows: $(printf '%s' "$out" | grep -c . || true)"
[ -z "$out" ] || printf '%s\n' "$out"
if [ "$status" -ne 0 ] || [ "$failed" -ne 0 ]; then
  echo "windows: FAILED: cargo test under Wine exited $status" >&2
  grep -E '^test .* FAILED$|^error: ' "$LOG" | sed 's/^/  /' >&2 || true
  exit 1
fi
if [ "$pytest_status" -ne 0 ]; then
  echo "windows: FAILED: pytest tests/windows exited $pytest_status" >&2
  exit 1
fi
echo "windows: ok"
