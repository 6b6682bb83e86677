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


def exact_sod(x, t, x0=1.0, gamma=5.0 / 3.0, left=(1.0, 0.0, 1.0), right=(0.125, 0.0, 0.1)):
    """Density of the exact solution (Toro ch. 4: Newton iteration on the pressure function)
    at positions x, time t > 0, for left/right states (rho, u, p)."""
    (rl, ul, pl), (rr, ur, pr) = left, right
    g = gamma
    cl, cr = math.sqrt(g * pl / rl), math.sqrt(g * pr / rr)

    def f(p, rk, pk, ck):
        if p > pk:  # shock (Toro Eq. 4.21)
            a, b = 2.0 / ((g + 1.0) * rk), (g - 1.0) / (g + 1.0) * pk
            q = math.sqrt(a / (p + b))
            return (p - pk) * q, q * (1.0 - 0.5 * (p - pk) / (p + b))
        # rarefaction (Toro Eq. 4.26)
        e = (g - 1.0) / (2.0 * g)
        return 2.0 * ck / (g - 1.0) * ((p / pk) ** e - 1.0), (p / pk) ** (-(g + 1.0) / (2.0 * g)) / (rk * ck)

    p = 0.5 * (pl + pr)
    for _ in range(100):
        fl, dl = f(p, rl, pl, cl)
        fr, dr = f(p, rr, pr, cr)
        step = (fl + fr + ur - ul) / (dl + dr)
        p = max(p - step, 1e-12)
        if abs(step) < 1e-14 * p:
            break
    us = 0.5 * (ul + ur) + 0.5 * (f(p, rr, pr, cr)[0] - f(p, rl, pl, cl)[0])

    def star_density(rk, pk):
        if p > pk:
            q = (g - 1.0) / (g + 1.0)
            return rk * (p / pk + q) / (q * p / pk + 1.0)
        return rk * (p / pk) ** (1.0 / g)

    rsl, rsr = star_density(rl, pl), star_density(rr, pr)
    s = (np.asarray(x, dtype=float) - x0) / t
    rho = np.empty_like(s)
    # left wave: a rarefaction for Sod (p* < pl)
    head, tail = ul - cl, us - cl * (p / pl) ** ((g - 1.0) / (2.0 * g))
    fan = rl * (2.0 / (g + 1.0) + (g - 1.0) / ((g + 1.0) * cl) * (ul - s)) ** (2.0 / (g - 1.0))
    # right wave: a shock (p* > pr)
    shock = ur + cr * math.sqrt((g + 1.0) / (2.0 * g) * p / pr + (g - 1.0) / (2.0 * g))
    assert p < pl and p > pr, "exact_sod: only the Sod wave pattern (rarefaction, shock)"
    rho[:] = np.where(s < head, rl, np.where(s < tail, fan, np.where(s < us, rsl, np.where(s < shock, rsr, rr))))
    return rho


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
    import h5py

    snap = args.snapshot or sorted(glob.glob(os.path.join(args.run_dir, "sodShock_*.hdf5")))[-1]
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
