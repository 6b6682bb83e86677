#!/usr/bin/env python3
"""Free piston on a gas spring, co-simulated: a Python master steps the sphfmu FMU (FMI 3.0,
through fmpy) and integrates the piston's Newton's law itself.

    M dv/dt = F_fluid - P0 * A,   dx/dt = v

The FMU gets the piston's position and velocity each communication step (the piston moves on
at that velocity inside the step) and returns the force of the gas on it. Linear theory: a
gas spring of stiffness gamma P0 A / L0, so omega = sqrt(gamma P0 A / (M L0)).

    python tools/free_piston.py --fmu target/fmu/sphfmu.fmu --out target/demo

writes free_piston.csv and free_piston.png and prints the measured period against theory.
Used by `make demo` and by tests/fmpy/test_fmu.py.
"""
import argparse
import math
import os
import sys

GAMMA, P0, AREA, L0 = 1.4, 1.0, 0.2, 1.0


def theory_period(mass):
    return 2.0 * math.pi / math.sqrt(GAMMA * P0 * AREA / (mass * L0))


def run(fmu_path, mass=2.0, v0=0.02, step=0.05, periods=1.15, threads=0, progress=False):
    """Run the co-simulation; return dict(t, x, v, force, crossings, period, theory)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    for name in ("piston.position", "piston.velocity", "piston.force", "threads"):
        if name not in vr:
            sys.exit(f"free_piston: {fmu_path} has no variable {name!r}; package models/free-piston2d.toml")
    unzipdir = extract(fmu_path)
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="free_piston")
    try:
        fmu.instantiate()
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setInt64([vr["threads"]], [threads])
        fmu.exitInitializationMode()
        t, x, v = 0.0, L0, v0
        rec = {"t": [], "x": [], "v": [], "force": []}
        crossings = []
        t_end = periods * theory_period(mass)
        n = int(math.ceil(t_end / step))
        for k in range(n):
            # inputs at the start of the step, then the step, then the master's own update
            fmu.setFloat64([vr["piston.position"], vr["piston.velocity"]],
                           [x, 0.1, 0.0, v, 0.0, 0.0])
            fmu.doStep(t, step)
            t += step
            force = fmu.getFloat64([vr["piston.force"]], nValues=3)[0]
            v += (force - P0 * AREA) / mass * step   # symplectic Euler
            x_new = x + v * step
            if (x - L0) * (x_new - L0) < 0.0:
                crossings.append(t - step + step * (x - L0) / (x - x_new))
            x = x_new
            for key, val in zip(("t", "x", "v", "force"), (t, x, v, force)):
                rec[key].append(val)
            if progress and k % 40 == 0:
                print(f"\r  t = {t:6.2f} / {t_end:.2f}  x = {x:.4f}", end="", flush=True)
        if progress:
            print()
        fmu.terminate()
    finally:
        fmu.freeInstance()
    rec["crossings"] = crossings
    rec["period"] = crossings[1] if len(crossings) >= 2 else float("nan")
    rec["theory"] = theory_period(mass)
    return rec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", default="target/fmu/sphfmu.fmu")
    ap.add_argument("--out", default="target/demo")
    ap.add_argument("--mass", type=float, default=2.0, help="piston mass per metre of depth (kg/m)")
    ap.add_argument("--step", type=float, default=0.05, help="communication step (s)")
    args = ap.parse_args()
    if not (args.mass > 0 and args.step > 0):
        sys.exit("free_piston: --mass and --step must be > 0")
    os.makedirs(args.out, exist_ok=True)
    print(f"free piston: M = {args.mass}, communication step {args.step} s, FMU {args.fmu}")
    r = run(args.fmu, mass=args.mass, step=args.step, progress=True)
    csv = os.path.join(args.out, "free_piston.csv")
    with open(csv, "w") as f:
        f.write("t,x,v,force\n")
        for row in zip(r["t"], r["x"], r["v"], r["force"]):
            f.write(",".join(f"{x:.10g}" for x in row) + "\n")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    omega = 2 * math.pi / r["theory"]
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax[0].plot(r["t"], r["x"], label="piston position (co-simulation)")
    ax[0].plot(r["t"], [L0 + 0.02 / omega * math.sin(omega * t) for t in r["t"]], "--",
               label="linear gas spring, same start")
    ax[0].set_ylabel("x (m)")
    ax[0].legend(loc="lower left")
    ax[1].plot(r["t"], r["force"], label="gas force on the piston (FMU output)")
    ax[1].axhline(P0 * AREA, color="gray", lw=0.8, label="P0 A (outside)")
    ax[1].set_ylabel("F (N/m)")
    ax[1].set_xlabel("t (s)")
    ax[1].legend(loc="lower left")
    fig.suptitle(f"sphfmu FMU + Python master: period {r['period']:.3f} s, "
                 f"gas-spring theory {r['theory']:.3f} s")
    png = os.path.join(args.out, "free_piston.png")
    fig.savefig(png, dpi=110)
    print(f"period {r['period']:.4f} s (zero crossings {['%.3f' % c for c in r['crossings']]}), "
          f"theory sqrt(gamma P0 A/(M L0)) -> {r['theory']:.4f} s, ratio {r['period'] / r['theory']:.4f}")
    print(f"wrote {csv} and {png}")


if __name__ == "__main__":
    main()
