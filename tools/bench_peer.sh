#!/usr/bin/env bash
# Side-by-side benchmark against PySPH on the 2D Noh problem (100^2 particles, gamma = 5/3,
# t = 0.6), both codes in this one run on this machine. Installs PySPH 1.0b2 from PyPI into
# target/peer-venv the first time (about 3.5 minutes; see ../shared/spec/peers.md §1.1).
# Usage: tools/bench_peer.sh [--threads N]   (default: all cores for both codes)
set -euo pipefail
cd "$(dirname "$0")/.."
THREADS=$(nproc)
if [[ "${1:-}" == "--threads" ]]; then THREADS=$2; fi
VENV=target/peer-venv
if [[ ! -f $VENV/.installed ]]; then
  python3 -m venv $VENV
  $VENV/bin/pip install --quiet --upgrade pip
  # PySPH's sdist compiles Cython against these; --no-build-isolation reuses them.
  $VENV/bin/pip install --quiet "numpy<3" cython mako pytools beaker cyarray compyle setuptools wheel h5py
  $VENV/bin/pip install --quiet --no-build-isolation pysph==1.0b2
  touch $VENV/.installed
fi
cargo build --release --quiet
exec $VENV/bin/python tools/bench_peer.py --threads "$THREADS"
