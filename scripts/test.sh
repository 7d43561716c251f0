#!/usr/bin/env bash
# Sets up a fresh machine (scripts/setup.sh) and runs every test: Rust (cargo test) and Python
# (pytest against the real daemon, real usd-core).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export TESSD_BIN="${CARGO_TARGET_DIR:-$PWD/target}/release/tessd"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
echo "== cargo test"
cargo test --workspace --release
echo "== pytest"
.venv/bin/python -m pytest tests -q -p no:cacheprovider
