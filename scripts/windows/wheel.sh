#!/usr/bin/env bash
# Builds the win_amd64 wheel of python/ (the tessd.exe daemon + the pure-Python client) on Linux:
# maturin's cross build for x86_64-pc-windows-gnu, linked with mingw.
#
#   bash scripts/windows/wheel.sh [OUT_DIR]        (default: dist/ at the repository's root)
#
# pip runs python/pyproject.toml's maturin backend in an isolated build environment (maturin
# comes from PyPI, as for `pip install ./python`); MATURIN_PEP517_ARGS passes it the target.
# cargo builds into $CARGO_TARGET_DIR (else the repository's target/), reusing a release cross
# build already there (`cargo build --release --target x86_64-pc-windows-gnu -p tessd`), so the
# wheel's tessd.exe is that same file. The mingw linker comes from .cargo/config.toml, else from
# CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER (set here when unset). Prints the wheel's path.
# Environment: PYTHON (default: the repository's .venv/bin/python, else python3).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/../.." && pwd)
OUT=${1:-$REPO/dist}
PY=${PYTHON:-}
if [ -z "$PY" ]; then
  if [ -x "$REPO/.venv/bin/python" ]; then PY=$REPO/.venv/bin/python; else PY=python3; fi
fi
command -v x86_64-w64-mingw32-gcc >/dev/null \
  || { echo "windows/wheel.sh: x86_64-w64-mingw32-gcc not found (scripts/setup.sh installs mingw)" >&2; exit 1; }
export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER=${CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER:-x86_64-w64-mingw32-gcc}
export CC_x86_64_pc_windows_gnu=${CC_x86_64_pc_windows_gnu:-x86_64-w64-mingw32-gcc}
export MATURIN_PEP517_ARGS="--target x86_64-pc-windows-gnu"
mkdir -p "$OUT"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessd-winwheel.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
"$PY" -m pip wheel --no-deps --disable-pip-version-check -q -w "$WORK" "$REPO/python" >&2
wheel=$(ls "$WORK"/tessd-*-win_amd64.whl 2>/dev/null || true)
[ -n "$wheel" ] && [ "$(echo "$wheel" | wc -l)" = 1 ] \
  || { echo "windows/wheel.sh: expected one tessd-*-win_amd64.whl, got: $(ls "$WORK")" >&2; exit 1; }
mv "$wheel" "$OUT/"
echo "$OUT/$(basename "$wheel")"
