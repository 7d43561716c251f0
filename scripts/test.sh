#!/usr/bin/env bash
# Sets up a fresh machine (scripts/setup.sh) and runs every test: Rust (cargo test) and Python
# (pytest against the real daemon, real usd-core; the B-Rep exporters against real OCP and FreeCAD;
# the FreeCAD workbench inside real FreeCAD).
set -euo pipefail
cd "$(dirname "$0")/.."
# Each step's heading carries the seconds since the start, so a CI log shows where its time goes.
START=$SECONDS
step() { echo "== $* [t+$((SECONDS - START)) s]"; }
step "setup (scripts/setup.sh)"
bash scripts/setup.sh
export TESSD_BIN="${CARGO_TARGET_DIR:-$PWD/target}/release/tessd"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$PWD/../shared/data}"
step "cargo test"
cargo test --workspace --release
step "windows (x86_64-pc-windows-gnu cross build, its Rust tests under Wine, tests/windows)"
bash scripts/windows/test.sh
# 20 s a target here: the kept corpora replay first, then ~15 s of new inputs each; the long
# runs (30 min a target) are docs/reliability.md's and bench/results/fuzz.md's.
FUZZ_SECONDS=${FUZZ_SECONDS:-20}
step "fuzz (every target $FUZZ_SECONDS s on its kept corpus)"
bash scripts/fuzz.sh "$FUZZ_SECONDS"
step "pytest (daemon, USD, demo, simplification)"
.venv/bin/python -m pytest tests -q -p no:cacheprovider --ignore=tests/compare --ignore=tests/brep \
  --ignore=tests/brep_build123d --ignore=tests/brep_freecad --ignore=tests/render_reference \
  --ignore=tests/freecad_plugin --ignore=tests/batch --ignore=tests/windows
step "soak (32 clients, every op, valid and invalid inputs, cancels; 60 s here, 10 min in docs/reliability.md)"
bash scripts/soak.sh 60
step "pytest (cross-checks against peer tools)"
.venv-bench/bin/python -m pytest tests/compare -q -p no:cacheprovider
# tests/brep (the exporter, the daemon's B-Rep ops against OCP, the real-file fixtures) needs
# nothing but OCP: it runs whole under both OCP releases the exporter supports.
step "pytest (B-Rep export and tessellation on real OpenCASCADE: OCP 7.9, cadquery 2.8's venv)"
.venv-cad/bin/python -m pytest tests/brep -q -p no:cacheprovider
step "pytest (asset-library batches on Dask: tessd.batch, cadquery 2.8's venv; usd-core from .venv)"
.venv-cad/bin/python -m pytest tests/batch -q -p no:cacheprovider
step "pytest (renders against the independent reference: OCP BRepMesh + Embree, cadquery 2.8's venv)"
.venv-cad/bin/python -m pytest tests/render_reference -q -p no:cacheprovider
step "pytest (B-Rep export and tessellation on real OpenCASCADE: OCP 8.0, build123d 0.13's venv)"
.venv-b123d/bin/python -m pytest tests/brep tests/brep_build123d -q -p no:cacheprovider
step "pytest (B-Rep export from FreeCAD 0.20, system python)"
PYTHONPATH=python:tests /usr/bin/python3 -m pytest tests/brep_freecad -q -p no:cacheprovider
step "FreeCAD workbench (console and GUI, real FreeCAD 0.20)"
bash tests/freecad_plugin/run.sh
step "examples (every example of examples/, outputs checked)"
bash scripts/run_examples.sh
step "wheel (pip install ./python: daemon + client in one wheel, fresh venv, cadquery example)"
bash scripts/wheel_check.sh
step "done"
