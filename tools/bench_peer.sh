#!/usr/bin/env bash
# Side-by-side benchmark against PySPH on the 2D Noh problem (100^2 particles, gamma = 5/3,
# t = 0.6), both codes in this one run on this machine. Installs PySPH 1.0b2 from PyPI into
# target/peer-venv the first time (about 3.5 minutes: PySPH's sdist compiles its Cython;
# https://pypi.org/project/PySPH/1.0b2/).
# Usage: tools/bench_peer.sh [--threads N] [--schemes psph,crksph] [--rounds N]
#   (default: all cores for both codes; PySPH's psph and crksph schemes — crksph takes ~7 min;
#   --rounds N runs everything N times interleaved and reports medians, PySPH's crksph once)
set -euo pipefail
cd "$(dirname "$0")/.."
THREADS=$(nproc)
SCHEMES=psph,crksph
ROUNDS=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --threads) THREADS=$2; shift 2 ;;
    --schemes) SCHEMES=$2; shift 2 ;;
    --rounds) ROUNDS=$2; shift 2 ;;
    *) echo "bench_peer.sh: unknown argument $1 (allowed: --threads N, --schemes LIST, --rounds N)" >&2; exit 2 ;;
  esac
done
VENV=target/peer-venv
if [[ ! -f $VENV/.installed ]]; then
  python3 -m venv $VENV
  $VENV/bin/pip install --quiet --upgrade pip
  # PySPH's sdist compiles Cython against these; --no-build-isolation reuses them.
  $VENV/bin/pip install --quiet "numpy<3" cython mako pytools beaker cyarray compyle setuptools wheel h5py
  $VENV/bin/pip install --quiet --no-build-isolation pysph==1.0b2
  touch $VENV/.installed
fi
cargo build --release --workspace --features sphfmu/mpi --quiet
exec $VENV/bin/python tools/bench_peer.py --threads "$THREADS" --schemes "$SCHEMES" --rounds "$ROUNDS"
