#!/usr/bin/env bash
# Sets up a fresh machine (scripts/setup.sh) and runs `tessd demo` on the bundled sample,
# writing its results to ./tessd-demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --demo
exec "${CARGO_TARGET_DIR:-target}/release/tessd" demo "$@"
