#!/usr/bin/env bash
# Idempotent set-up: every Debian and Python package xpbd-bench needs.
# Run as root on Debian 12. Safe to run again: it only installs what is missing.
set -euo pipefail

DEB_PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libsuitesparse-dev libopenblas0-pthread
  libhdf5-dev libtomlplusplus-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libhypre-dev trilinos-all-dev libptscotch-dev openmpi-bin libopenmpi-dev
  tetgen gmsh
  clang libclang-rt-14-dev llvm   # make fuzz (libFuzzer, sanitizer runtimes, llvm-symbolizer)
)
# nanobind + scikit-build-core: the Python package xpbd_bench (python/, pyproject.toml); pytest: its
# tests; tqdm: figures/run.py's status line.
PY_PACKAGES=(numpy h5py matplotlib scipy pyamg nanobind scikit-build-core pytest tqdm)

missing=()
for p in "${DEB_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# One Python for everything: the python3 on PATH (plots, tests, pyamg cross-check).
PY=${PYTHON:-python3}
if ! "$PY" -c 'import numpy, h5py, matplotlib, scipy, pyamg, nanobind, scikit_build_core, pytest, tqdm' 2>/dev/null; then
  echo "setup: installing Python packages: ${PY_PACKAGES[*]}"
  "$PY" -m pip install -q --disable-pip-version-check "${PY_PACKAGES[@]}"
fi
