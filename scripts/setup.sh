#!/usr/bin/env bash
# Sets up a fresh machine for tessd: system packages, the Rust build, and the Python venvs with
# pinned versions. Safe to run again; it only does what is missing. `--demo`: only what
# `tessd demo` needs: the release build (its inputs are compiled into the binary) and, for its
# pictures, the Vulkan loader and Mesa's software Vulkan driver (lavapipe) when missing; no venv,
# nothing downloaded but the crates and those two packages. `--fuzz`: only what scripts/fuzz.sh
# needs, the nightly toolchain and cargo-fuzz.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null || PY=python3

# Installs those of the given Debian packages that are missing (as root, or through sudo).
apt_install() {
  local missing=() p
  for p in "$@"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    local SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
    $SUDO apt-get update -qq
    # `env` inside sudo: sudo drops the caller's DEBIAN_FRONTEND. No progress bars in logs.
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq -o Dpkg::Use-Pty=0 \
      --no-install-recommends "${missing[@]}"
  fi
}

# Python venvs, pinned; each is rebuilt only when its requirements file changes.
#   .venv        tests: usd-core, numpy, bpy, pytest       (python/requirements-test.txt)
#   .venv-bench  peer tools for cross-checks and benchmarks: pymeshlab, matplotlib
#                                                          (bench/requirements-bench.txt)
#   .venv-cad    B-Rep tests (tests/brep) on OCP 7.9: cadquery 2.8 + cadquery-ocp 7.9, pytest,
#                dask[distributed] (tessd.batch, tests/batch)
#                                                          (python/requirements-cad.txt)
#   .venv-b123d  B-Rep tests (tests/brep, tests/brep_build123d) on OCP 8.0: build123d 0.13 +
#                cadquery-ocp-novtk 8.0, numpy, pytest     (python/requirements-build123d.txt)
make_venv() {
  local dir=$1 reqs=$2
  if [ ! -x "$dir/bin/python" ]; then
    echo "setup: creating $dir with $PY"
    "$PY" -m venv "$dir"
  fi
  if ! cmp -s "$reqs" "$dir/.requirements-installed" 2>/dev/null; then
    echo "setup: installing $reqs into $dir"
    "$dir/bin/python" -m pip install -q --upgrade pip
    "$dir/bin/python" -m pip install -q -r "$reqs"
    cp "$reqs" "$dir/.requirements-installed"
  fi
}
# The fuzzers' tools (scripts/fuzz.sh): the nightly toolchain (libFuzzer's sanitizer flags are
# nightly-only) and cargo-fuzz, pinned, built from crates.io.
CARGO_FUZZ_VERSION=0.13.2
fuzz_tools() {
  if ! rustup toolchain list | grep -q '^nightly-'; then
    echo "setup: installing the nightly toolchain"
    rustup toolchain install nightly --profile minimal
  fi
  if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "setup: installing cargo-fuzz $CARGO_FUZZ_VERSION"
    cargo install cargo-fuzz --version "$CARGO_FUZZ_VERSION" --locked --quiet
  fi
}
if [ "${1:-}" = "--fuzz" ]; then
  fuzz_tools
  exit 0
fi

# What `tessd demo` needs besides the binary: its pictures render on Vulkan, without a GPU on
# lavapipe, so the loader and the driver (tests/demo checks that this list is all `--demo`
# installs).
DEMO_APT_PACKAGES=(libvulkan1 mesa-vulkan-drivers)
if [ "${1:-}" = "--demo" ]; then
  if command -v dpkg >/dev/null && command -v apt-get >/dev/null; then
    apt_install "${DEMO_APT_PACKAGES[@]}"
  else
    # Not Debian or Ubuntu: the demo still writes everything but its pictures without them.
    echo "setup: no apt-get here; for the demo's pictures install the Vulkan loader and Mesa's" \
      "Vulkan drivers (lavapipe) with this system's package manager"
  fi
else
  # System packages the tests need (none are needed by the build itself yet): the renderer's
  # Vulkan (lavapipe), as for the demo; useradd and mount/umount for tests/reliability (a
  # second user, a tmpfs); an X server with no screen (Xvfb) and xdotool for `tessd view`'s
  # real windows and real key presses (tests/view).
  APT_PACKAGES=("${DEMO_APT_PACKAGES[@]}" passwd mount xvfb xauth xdotool)
  apt_install "${APT_PACKAGES[@]}"
  make_venv .venv python/requirements-test.txt
  make_venv .venv-bench bench/requirements-bench.txt
  make_venv .venv-cad python/requirements-cad.txt
  make_venv .venv-b123d python/requirements-build123d.txt
  # FreeCAD 0.20's Python modules (FreeCAD.so, Part.so in /usr/lib/freecad-python3/lib) for the
  # FreeCAD exporter's tests (tests/brep_freecad), which the system python3 they are built for
  # runs, with its pytest and numpy; and FreeCAD itself (freecad-python3: freecadcmd, the GUI,
  # PySide2) for the workbench's tests (tests/freecad_plugin/run.sh).
  FREECAD_APT_PACKAGES=(libfreecad-python3-0.20 freecad-python3 python3-pytest python3-numpy)
  apt_install "${FREECAD_APT_PACKAGES[@]}"
  # Windows (issue 37): mingw links the x86_64-pc-windows-gnu cross build (g++ for
  # meshoptimizer's C++), Wine 8 runs its tests (scripts/windows/test.sh), under Xvfb, as
  # Wine's Vulkan needs an X display; libvkd3d1 gives Wine's d3d12 an adapter that refuses its
  # device, which the GPU tests pass over to Vulkan; the macOS targets are type-checked only
  # (.ci/run).
  WINDOWS_APT_PACKAGES=(gcc-mingw-w64-x86-64 g++-mingw-w64-x86-64 wine64 libvkd3d1 xvfb xauth)
  apt_install "${WINDOWS_APT_PACKAGES[@]}"
  RUST_TARGETS=(x86_64-pc-windows-gnu aarch64-apple-darwin x86_64-apple-darwin)
  missing_targets=()
  for t in "${RUST_TARGETS[@]}"; do
    rustup target list --installed | grep -qx "$t" || missing_targets+=("$t")
  done
  if [ ${#missing_targets[@]} -gt 0 ]; then
    echo "setup: adding the Rust targets ${missing_targets[*]}"
    rustup target add "${missing_targets[@]}"
  fi
  fuzz_tools
fi

echo "setup: building tessd (release)"
cargo build --release -p tessd --quiet
