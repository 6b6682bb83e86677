#!/usr/bin/env python3
"""Read a SWIFT run of examples/HydroTests/SodShock_BCC_3D and print the two figures issue 19
compares with `models/bench/sod3d.toml`: particle-updates per second and L1(rho).

This is a measurement aid for BENCHMARKS.md, not part of the solver or its tests: SWIFT is not
in a package registry, so the user builds and runs it (BENCHMARKS.md gives the commands) and
points this script at the run's folder. Nothing in the repository fetches or needs SWIFT.

  python3 tools/swift_sod3d.py RUN_DIR [--snapshot sodShock_0001.hdf5]

- rate: sum of Updates over sum of wall-clock over the steps after step 0, from SWIFT's
  timesteps file (the file `timesteps_*.txt` / `timesteps.txt` SWIFT writes in RUN_DIR).
- L1(rho): mean over particles with 0.5 <= x <= 1.5 of |rho - rho_exact|, the definition
  `sphfmu run` uses for its shock-tube rows (src/verify/mod.rs, shock_tube_errors), against the
  exact Riemann solution (Toro, Riemann Solvers and Numerical Methods for Fluid Dynamics,
  3rd ed., ch. 4) of the Sod states, gamma = 5/3, interface at x = 1, at the snapshot's time.
Needs numpy and h5py.
"""

import argparse
import glob
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from verify_metrics import riemann_shock  # noqa: E402


def exact_sod(x, t, x0=1.0, gamma=5.0 / 3.0, left=(1.0, 1.0), right=(0.125, 0.1)):
    """Density of the exact solution at positions x, time t > 0, for gases at rest with left
    and right states (rho, P), the left one at the higher pressure: p* and the shock speed from
    verify_metrics.riemann_shock (Toro ch. 4), then the star densities (Toro Eqs. 4.50, 4.53),
    u* behind the shock from its mass flux, and the left rarefaction fan (Toro Eq. 4.56)."""
    (rl, pl), (rr, pr) = left, right
    g = gamma
    p, shock = riemann_shock((rl, pl, g), (rr, pr, g))
    q = (g - 1.0) / (g + 1.0)
    rsr = rr * (p / pr + q) / (q * p / pr + 1.0)  # behind the shock
    rsl = rl * (p / pl) ** (1.0 / g)  # behind the rarefaction
    us = shock * (1.0 - rr / rsr)  # rho_R S = rho*_R (S - u*)
    cl = math.sqrt(g * pl / rl)
    head, tail = -cl, us - cl * (p / pl) ** ((g - 1.0) / (2.0 * g))
    s = (np.asarray(x, dtype=float) - x0) / t
    fan = rl * (2.0 / (g + 1.0) - (g - 1.0) / ((g + 1.0) * cl) * s) ** (2.0 / (g - 1.0))
    return np.where(s < head, rl, np.where(s < tail, fan, np.where(s < us, rsl, np.where(s < shock, rsr, rr))))


def swift_rate(run_dir):
    files = sorted(glob.glob(os.path.join(run_dir, "timesteps*.txt")))
    if not files:
        sys.exit(f"swift_sod3d: no timesteps*.txt in {run_dir}")
    updates = wall = 0.0
    steps = 0
    for line in open(files[-1]):
        if line.startswith("#") or not line.strip():
            continue
        c = line.split()
        # Step Time Scale-factor Redshift Time-step Time-bins(min max) Updates g-Updates
        # s-Updates Sink-Updates b-Updates Wall-clock Props Dead-time
        if int(c[0]) == 0:
            continue
        updates += float(c[7])
        wall += float(c[12]) / 1000.0  # SWIFT prints wall-clock in ms
        steps += 1
    return updates, wall, steps


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--snapshot", default=None, help="default: the last sodShock_*.hdf5")
    args = ap.parse_args()
    updates, wall, steps = swift_rate(args.run_dir)
    print(f"steps after step 0: {steps}, updates {updates:.6g}, wall-clock {wall:.3f} s, "
          f"rate {updates / wall:.4e} particle-updates/s")
    try:
        import h5py
    except ImportError:
        sys.exit("swift_sod3d: reading the snapshot needs h5py (pip install h5py)")
    snaps = sorted(glob.glob(os.path.join(args.run_dir, "sodShock_*.hdf5")))
    if not args.snapshot and not snaps:
        sys.exit(f"swift_sod3d: no sodShock_*.hdf5 snapshot in {args.run_dir}")
    snap = args.snapshot or snaps[-1]
    with h5py.File(os.path.join(args.run_dir, os.path.basename(snap)), "r") as fh:
        t = float(np.atleast_1d(fh["Header"].attrs["Time"])[0])
        x = fh["PartType0/Coordinates"][:, 0]
        rho = fh["PartType0/Densities"][:]
    sel = (x >= 0.5) & (x <= 1.5)
    l1 = float(np.mean(np.abs(rho[sel] - exact_sod(x[sel], t))))
    print(f"{os.path.basename(snap)}: t = {t:.4f}, {sel.sum()} particles in 0.5 <= x <= 1.5, "
          f"L1(rho) = {l1:.5f}")


if __name__ == "__main__":
    main()
