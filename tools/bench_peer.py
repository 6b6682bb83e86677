"""Run the 2D Noh problem in PySPH (PSPH, the closest scheme with a cheap force loop, and
its CRKSPH) and in sphfmu (standard SPH, models/noh2d.toml) in one run, and print
particle-updates/s side by side with the ratio and L1(rho) for r < 0.5 (pysph/examples/gas_dynamics/noh.py).
Called by tools/bench_peer.sh inside the PySPH venv."""
import argparse
import csv
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
T_END = 0.6


def noh_l1(x, y, rho, t=T_END):
    r = np.hypot(x, y)
    sel = r < 0.5
    exact = np.where(r < t / 3.0, 16.0, 1.0 + t / np.maximum(r, 1e-12))
    return float(np.mean(np.abs(rho[sel] - exact[sel])))


def run_pysph(scheme, threads, outdir):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    base = [sys.executable, "-m", "pysph.examples.gas_dynamics.noh", "--scheme", scheme]
    if threads > 1:
        base.append("--openmp")
    # warm-up: compiles the generated Cython (not timed)
    subprocess.run(base + ["-d", outdir + "_warm", "--max-steps", "3"], env=env, check=True,
                   capture_output=True, text=True)
    r = subprocess.run(base + ["-d", outdir], env=env, check=True, capture_output=True, text=True)
    text = r.stdout + r.stderr
    for log in glob.glob(os.path.join(outdir, "*.log")):
        text += open(log).read()
    took = re.findall(r"Run took:\s*([0-9.eE+-]+)", text)
    iters = re.findall(r"iteration\s*[:=]?\s*(\d+)", text)
    if not took:
        raise RuntimeError("PySPH: no 'Run took' line in its output")
    secs = float(took[-1])
    from pysph.solver.utils import load, get_files
    files = get_files(outdir)
    data = load(files[-1])
    fluid = data["arrays"]["fluid"]
    steps = int(iters[-1]) if iters else int(round(T_END / 1e-3))
    n = len(fluid.x)
    return {"code": "PySPH 1.0b2", "scheme": scheme, "threads": threads, "particles": n,
            "steps": steps, "seconds": secs, "updates_per_s": n * steps / secs,
            "l1_rho": noh_l1(fluid.x, fluid.y, fluid.rho)}


def scheme_case(scheme, path):
    """models/noh2d.toml with `scheme` and that preset's own kernel, eta, integrator and CFL
    (the [kernel] table and the integrator/cfl keys dropped), as each PySPH scheme runs
    with its own: scheme against scheme."""
    text = open(os.path.join(ROOT, "models", "noh2d.toml")).read()
    text = re.sub(r"\[kernel\]\nname = .*\neta = .*\n", "", text)
    text = re.sub(r"\[scheme\]\n(.*\n)*?\n", f'[scheme]\nname = "{scheme}"\n\n', text, count=1)
    text = re.sub(r"integrator = .*\n|cfl = .*\n", "", text)
    text = text.replace('name = "noh2d"', f'name = "noh2d-{scheme}"')
    open(path, "w").write(text)
    return path


def run_sphfmu(threads, outdir, scheme="standard"):
    exe = os.path.join(ROOT, "target", "release", "sphfmu")
    case = os.path.join(ROOT, "models", "noh2d.toml")
    if scheme != "standard":
        case = scheme_case(scheme, outdir + ".toml")
    r = subprocess.run([exe, "run", case, "--out", outdir,
                        "--quiet", "--threads", str(threads)], check=True, capture_output=True, text=True)
    s = json.load(open(os.path.join(outdir, "summary.json")))
    final = sorted(glob.glob(os.path.join(outdir, "snapshot_*.csv")))[-1]
    with open(final) as f:
        # headers read `name [unit]`
        rows = [{k.split(" [")[0]: v for k, v in q.items()} for q in csv.DictReader(f)]
    x = np.array([float(q["x"]) for q in rows])
    y = np.array([float(q["y"]) for q in rows])
    rho = np.array([float(q["rho"]) for q in rows])
    return {"code": "sphfmu", "scheme": scheme, "threads": threads, "particles": s["particles"],
            "steps": s["steps"], "seconds": s["wall_seconds"],
            "updates_per_s": s["particle_updates_per_second"], "l1_rho": noh_l1(x, y, rho)}


def median_row(runs):
    """One row for a code and scheme from its rounds: the run of median rate (its seconds, steps
    and L1 with it), every round's rate kept in `rates`."""
    ranked = sorted(runs, key=lambda r: r["updates_per_s"])
    row = dict(ranked[(len(ranked) - 1) // 2])
    row["rates"] = [r["updates_per_s"] for r in runs]
    return row


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--schemes", default="psph,crksph")
    # One run of each on this 2-vCPU VM moves the ratio between 16.8x and 20.0x with no code
    # change (BENCHMARKS.md, 2026-12-07): rounds run everything again, interleaved, and the
    # table reads each code's median round.
    ap.add_argument("--rounds", type=int, default=1, help="interleaved rounds (median reported)")
    ap.add_argument("--once", default="crksph",
                    help="PySPH schemes run in the first round only (PySPH's CRKSPH takes ~6 min)")
    args = ap.parse_args()
    if args.rounds < 1:
        sys.exit(f"bench_peer.py: --rounds must be >= 1, got {args.rounds}")
    once = set(args.once.split(",")) & set(args.schemes.split(",")) if args.once else set()
    runs = {}  # (code, scheme) -> [run, ...] in round order
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.rounds):
            tag = f"-{k}"
            ours = run_sphfmu(args.threads, os.path.join(tmp, "sphfmu" + tag))
            runs.setdefault(("sphfmu", "standard"), []).append(ours)
            for scheme in args.schemes.split(","):
                # ours with the same scheme, then PySPH's, back to back
                r = run_sphfmu(args.threads, os.path.join(tmp, "sphfmu-" + scheme + tag), scheme)
                runs.setdefault(("sphfmu", scheme), []).append(r)
                if k == 0 or scheme not in once:
                    r = run_pysph(scheme, args.threads, os.path.join(tmp, scheme + tag))
                    runs.setdefault((r["code"], scheme), []).append(r)
    rows = [median_row(v) for v in runs.values()]
    ours = rows[0]
    what = "one run" if args.rounds == 1 else f"median of {args.rounds} interleaved rounds" + (
        f" ({', '.join(sorted(once))}: PySPH's once)" if once else "")
    print(f"Noh 2D, 100^2 particles, t = {T_END}, {args.threads} thread(s), {what} (tools/bench_peer.sh)")
    print("| code | scheme | particles | steps | seconds | particle-updates/s | rounds' rates | sphfmu standard / this | sphfmu same scheme / this | L1(rho), r < 0.5 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    same = {r["scheme"]: r for r in rows if r["code"] == "sphfmu"}
    for r in rows:
        ratio = ours["updates_per_s"] / r["updates_per_s"]
        r["standard_ratio"] = ratio
        r["same_scheme_ratio"] = same[r["scheme"]]["updates_per_s"] / r["updates_per_s"]
        spread = ", ".join(f"{x:.3g}" for x in r["rates"])
        print(f"| {r['code']} | {r['scheme']} | {r['particles']} | {r['steps']} | {r['seconds']:.2f} | "
              f"{r['updates_per_s']:.3e} | {spread} | {ratio:.1f}x | {r['same_scheme_ratio']:.1f}x | {r['l1_rho']:.3f} |")
    out = os.path.join(ROOT, "target", "bench-peer.json")
    json.dump(rows, open(out, "w"), indent=2)
    print(f"(also written to {out})")


if __name__ == "__main__":
    main()
