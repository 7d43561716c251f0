#!/usr/bin/env bash
# Soak test (issue 18): one real daemon, 32 clients issuing a random mix of every operation with
# valid and invalid inputs, random cancels and dropped connections, for SECONDS (default 600).
# Passes when no request failed, the daemon's idle RSS at the end is within 10 % of its idle RSS
# after the warm-up, its threads and descriptors are back to that count, and no temp file is
# left. Needs the release binary ($TESSD_BIN or target/release/tessd) and scripts/setup.sh's venv.
#
#   bash scripts/soak.sh [SECONDS] [--clients N] [--seed S]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
shift || true
export TESSD_BIN="${TESSD_BIN:-${CARGO_TARGET_DIR:-$PWD/target}/release/tessd}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
[ -x "$TESSD_BIN" ] || cargo build --release -p tessd
exec .venv/bin/python tests/soak/soak.py --seconds "$seconds" --clients 32 "$@"
