#!/usr/bin/env bash
# Sets up a fresh machine for tessd: system packages, the Rust build, and the Python test venv
# (.venv) with pinned versions. Safe to run again; it only does what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null || PY=python3

# System packages the tests need (none are needed by the build itself yet).
APT_PACKAGES=()
missing=()
for p in "${APT_PACKAGES[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi

# Python test venv, pinned (requirements live in python/requirements-test.txt).
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv with $PY"
  "$PY" -m venv .venv
fi
if ! cmp -s python/requirements-test.txt .venv/.requirements-installed 2>/dev/null; then
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -r python/requirements-test.txt
  cp python/requirements-test.txt .venv/.requirements-installed
fi

echo "setup: building tessd (release)"
cargo build --release -p tessd --quiet
