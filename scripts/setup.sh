#!/usr/bin/env bash
# Installs what rbc-toolkit needs on a fresh Debian machine with the Rust toolchain:
# the HDF5 C library (for results.h5), cargo-nextest (the test runner) and h5py
# (the tests check that results.h5 reads back in Python). Idempotent.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ] && command -v sudo >/dev/null; then SUDO=sudo; fi
if ! pkg-config --exists hdf5 2>/dev/null; then
  echo "setup: installing libhdf5-dev and pkg-config" >&2
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq libhdf5-dev pkg-config >/dev/null
fi
if ! cargo nextest --version >/dev/null 2>&1; then
  echo "setup: installing cargo-nextest" >&2
  cargo install cargo-nextest --locked
fi
if command -v python3 >/dev/null && ! python3 -c 'import h5py, numpy' >/dev/null 2>&1; then
  echo "setup: installing h5py and numpy (Python reader check of results.h5)" >&2
  python3 -m pip install -q h5py numpy
fi
