#!/usr/bin/env bash
# OpenSubdiv side of the subdivision benchmark: installs Debian's libosd-dev (OpenSubdiv 3.5)
# if missing and builds bench/subdiv/osd_bench.cpp into bench/out/subdiv/osd_bench.
# Idempotent: skips the install when the headers are there and the build when the binary is
# newer than the source (set FORCE=1 to rebuild).
#
#   bash bench/subdiv/setup_osd.sh
set -euo pipefail
cd "$(dirname "$0")/../.."

if [ ! -f /usr/include/opensubdiv/far/topologyRefiner.h ] || ! ldconfig -p 2>/dev/null | grep -q 'libosdCPU\.so'; then
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    if ! $SUDO apt-get install -y libosd-dev; then
        $SUDO apt-get update
        $SUDO apt-get install -y libosd-dev
    fi
fi
if ! command -v g++ >/dev/null 2>&1; then
    echo "setup_osd.sh: g++ is missing (apt-get install g++)" >&2
    exit 1
fi

SRC=bench/subdiv/osd_bench.cpp
OUT=bench/out/subdiv/osd_bench
mkdir -p "$(dirname "$OUT")"
if [ "${FORCE:-0}" = 1 ] || [ ! -x "$OUT" ] || [ "$SRC" -nt "$OUT" ]; then
    g++ -O2 -std=c++14 -Wall -Wextra -o "$OUT" "$SRC" -losdCPU
    echo "built $OUT"
else
    echo "$OUT is up to date"
fi
