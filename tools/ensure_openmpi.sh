#!/usr/bin/env bash
# Make sure Open MPI is here for the `mpi` feature (rsmpi): its build probes `mpicc -show` for
# the compile and link flags (libopenmpi-dev), and `mpirun` (openmpi-bin) starts the ranks of
# `mpirun -n R sphfmu run CASE` and of the tests. Installs Debian's packages when either is
# missing.
#
# Usage: tools/ensure_openmpi.sh [--check]   (--check: report only, exit 1 when missing)
set -euo pipefail

if command -v mpicc >/dev/null 2>&1 && command -v mpirun >/dev/null 2>&1 \
  && mpicc -show >/dev/null 2>&1; then
  echo "Open MPI: present ($(mpirun --version 2>/dev/null | head -n1))"
  exit 0
fi
if [ "${1:-}" = "--check" ]; then
  echo "Open MPI: missing (mpicc or mpirun not found)"
  exit 1
fi
echo "Open MPI: missing; installing Debian's libopenmpi-dev and openmpi-bin (the mpi feature)"
"$(dirname "$0")/apt_install.sh" "Open MPI" libopenmpi-dev openmpi-bin
exec "$0" --check
