#!/usr/bin/env bash
# Installs what rbc-toolkit needs on a fresh Debian machine with the Rust toolchain:
# the HDF5 C library (for results.h5), cargo-nextest (the test runner), h5py
# (the tests check that results.h5 reads back in Python) and ParaView's pvpython
# (the tests read the .xmf files of `rbc-sweep --xdmf` back with it). Idempotent.
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
if ! command -v pvpython >/dev/null; then
  # Debian's ParaView 5.11 (about 255 MB to download, 3-4 minutes): its XDMF Reader is the one
  # users open the .xmf files with; meshio cannot read their hyperslabs (data-schema/src/xdmf.rs)
  echo "setup: installing ParaView (pvpython reads the .xmf files of rbc-sweep --xdmf back)" >&2
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends paraview python3-paraview >/dev/null
fi
