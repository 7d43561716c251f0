#!/usr/bin/env bash
# Runs a Windows executable (x86_64-pc-windows-gnu) under Wine: cargo's runner for that target
# (.cargo/config.toml), so `cargo test --target x86_64-pc-windows-gnu` and `cargo run` run the
# binaries here; usable by hand too: scripts/windows/wine-run.sh path/to/x.exe args...
#
# TEST HARNESS ONLY: it uses a private Wine prefix (never the user's ~/.wine) with the
# bcryptprimitives.dll shim (scripts/windows/bcryptprimitives_shim.c) in its system32, which
# Rust programs need under Wine 8. Nothing of this is shipped.
#
# Prefix: $TESSD_WINEPREFIX, else <target dir>/wine-prefix, where the target dir is
# $CARGO_TARGET_DIR, else the folder above `x86_64-pc-windows-gnu/` in the executable's path,
# else the repository's target/. It is created once (wineboot -i, under a lock, so concurrent
# first runs wait for each other); the shim is rebuilt when its source changes. Concurrent runs
# share the prefix's one wineserver, which is fine. WINEDEBUG is -all (TESSD_WINEDEBUG overrides it, for debugging).
# The exit status is the program's.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
if [ $# -lt 1 ]; then
  echo "usage: $0 <program.exe> [args...]" >&2
  exit 2
fi
WINE=$(command -v wine64 || true)
[ -n "$WINE" ] || WINE=/usr/lib/wine/wine64
if [ ! -x "$WINE" ]; then
  echo "wine-run: wine64 not found (install the wine64 package: scripts/setup.sh does)" >&2
  exit 127
fi
WINESERVER=$(command -v wineserver || true)
[ -n "$WINESERVER" ] || WINESERVER=/usr/lib/wine/wineserver
MINGW_CC=${CC_x86_64_pc_windows_gnu:-x86_64-w64-mingw32-gcc}

exe=$1
if [ -n "${TESSD_WINEPREFIX:-}" ]; then
  prefix=$TESSD_WINEPREFIX
else
  if [ -n "${CARGO_TARGET_DIR:-}" ]; then
    target_dir=$CARGO_TARGET_DIR
  else
    abs_exe=$(realpath -m -- "$exe")
    case "$abs_exe" in
      */x86_64-pc-windows-gnu/*) target_dir=${abs_exe%%/x86_64-pc-windows-gnu/*} ;;
      *) target_dir=$(cd "$HERE/../.." && pwd)/target ;;
    esac
  fi
  prefix=$target_dir/wine-prefix
fi
mkdir -p "$prefix"
prefix=$(realpath -- "$prefix")
export WINEPREFIX=$prefix
export WINEDEBUG=${TESSD_WINEDEBUG:--all}
# No Wine pop-ups (Gecko/Mono installers, crash dialogs) in a headless run.
export WINEDLLOVERRIDES="${WINEDLLOVERRIDES:+$WINEDLLOVERRIDES;}mscoree,mshtml=;winedbg.exe="

shim_src=$HERE/bcryptprimitives_shim.c
shim_dll=$prefix/drive_c/windows/system32/bcryptprimitives.dll
shim_stamp=$prefix/.tessd-shim.sha256
want=$(sha256sum "$shim_src" | cut -d' ' -f1)
if [ ! -f "$shim_dll" ] || [ "$(cat "$shim_stamp" 2>/dev/null)" != "$want" ]; then
  (
    flock 9
    # Another run may have done it while this one waited for the lock.
    if [ ! -f "$prefix/system.reg" ]; then
      echo "wine-run: creating the Wine prefix $prefix" >&2
      "$WINE" wineboot -i >/dev/null 2>&1 || true
      "$WINESERVER" -w
      [ -f "$prefix/system.reg" ] || { echo "wine-run: wineboot did not create $prefix" >&2; exit 1; }
    fi
    if [ ! -f "$shim_dll" ] || [ "$(cat "$shim_stamp" 2>/dev/null)" != "$want" ]; then
      "$MINGW_CC" -shared -O2 -o "$shim_dll.tmp" "$shim_src" -ladvapi32
      mv -f "$shim_dll.tmp" "$shim_dll"
      echo "$want" >"$shim_stamp"
    fi
  ) 9>"$prefix/.tessd-setup.lock"
fi
# A program that ends on "wine client error" lost its wineserver (Wine's own failure, seen once
# in ~80 binaries when a run started while the previous run's server was exiting), not a test's:
# it runs again, once, and says so. Any other status is the program's.
err=$(mktemp)
trap 'rm -f "$err"' EXIT
status=0
"$WINE" "$@" 2> >(tee "$err" >&2) || status=$?
wait
if [ "$status" -ne 0 ] && grep -q '^wine client error' "$err"; then
  echo "wine-run: Wine lost its wineserver (not the program's failure); running $exe again" >&2
  status=0
  "$WINE" "$@" || status=$?
fi
exit "$status"
