"""The performance goals of `make bench`, each printed with its figure, what it is measured
against, the target and pass/short.

Reads what `make bench` measured just before in the same run: the throughput table
(target/bench.json, `sphfmu bench`) and the side-by-side with PySPH (target/bench-peer.json,
tools/bench_peer.sh). Runs the rest itself, back to back: the 3D Sod of
models/bench/sod3d.toml, the cost of CRKSPH and Rosswog F1 against standard SPH on one periodic box,
and the closed tank on 1 and 2 threads (speed-up, determinism, thread-count independence).
Our own baselines, per CPU model, are in tools/bench_baselines.json (see BENCHMARKS.md).

Usage: python3 tools/bench_goals.py [--skip-runs] [--out target/bench-goals.md]
                                    [--table target/bench.json] [--peer target/bench-peer.json]
  --skip-runs: only the goals that need no run of their own (table and peer files).
Exit status 0 whatever the verdicts (a benchmark reports; it does not fail a build).
"""
import argparse
import filecmp
import glob
import json
import os
import re
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXE = os.path.join(ROOT, "target", "release", "sphfmu")


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def load_json(path):
    try:
        return json.load(open(path))
    except (OSError, ValueError):
        return None


def run(case, out, threads=2, scheme=None):
    cmd = [EXE, "run", case, "--out", out, "--quiet", "--threads", str(threads)]
    if scheme:
        cmd += ["--scheme", scheme]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.load(open(os.path.join(out, "summary.json")))


def preset_defaults():
    """Each preset's kernel, eta, integrator and CFL, as `sphfmu run --help` lists them."""
    text = subprocess.run([EXE, "run", "--help"], check=True, capture_output=True,
                          text=True).stdout
    found = {}
    lines = text.splitlines()
    for i, line in enumerate(lines[:-1]):
        m = re.match(r"^  (\S+)\s", line)
        d = re.match(r"^\s+\[(\S+) eta ([0-9.]+), (\S+), CFL ([0-9.]+)\]", lines[i + 1])
        if m and d:
            found[m.group(1)] = d.groups()
    return found


def box_case(path, scheme, kernel, eta, integrator, cfl):
    """A 2D periodic box of 200^2 particles on a lattice perturbed by 10 % of the spacing
    (the throughput table's box, `sphfmu bench`), gas at rest, t = 0.3, with the given
    scheme, kernel, eta, integrator and CFL: the same case and neighbour number for both
    sides of a cost ratio. (Chosen while Rosswog F1 at its preset still stopped on the 2D Noh
    problem; a box at rest also keeps the step count the same on both sides.)"""
    text = f"""[case]
name = "cost-{scheme}"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
boundary = ["periodic", "periodic"]
[eos]
type = "ideal-gas"
gamma = 1.6666666666666667
[kernel]
name = "{kernel}"
eta = {eta}
[scheme]
name = "{scheme}"
[time]
t_end = 0.3
integrator = "{integrator}"
cfl = {cfl}
[output]
snapshot_every = 0.0
formats = ["csv"]
[[region]]
spacing = 0.005
density = 1.0
pressure = 1.0
[perturbation]
amplitude = 0.1
seed = 7
"""
    open(path, "w").write(text)
    return path


class Goals:
    def __init__(self):
        self.rows = []

    def add(self, goal, figure, against, target, ok, note=""):
        verdict = "unmeasured" if ok is None else ("pass" if ok else "short")
        self.rows.append({"goal": goal, "figure": figure, "against": against,
                          "target": target, "verdict": verdict, "note": note})

    def markdown(self):
        out = ["| goal | figure | measured against | target | verdict |",
               "|---|---|---|---|---|"]
        for r in self.rows:
            note = f" ({r['note']})" if r["note"] else ""
            out.append(f"| {r['goal']} | {r['figure']}{note} | {r['against']} | {r['target']} | "
                       f"**{r['verdict']}** |")
        return "\n".join(out)


def table_goals(g, table):
    if not table:
        g.add("force loop pairs/s per core", "-", "target/bench.json", ">= 1e8", None,
              "run `sphfmu bench --json target/bench.json` first")
        g.add("cost linear in N (1e4..1e6)", "-", "target/bench.json", "within +-15 %", None)
        return
    rows = table
    worst = min(rows, key=lambda r: r["force_loop_pairs_per_second_per_thread"])
    best = max(rows, key=lambda r: r["force_loop_pairs_per_second_per_thread"])
    g.add("force loop pairs/s per core", f"{worst['force_loop_pairs_per_second_per_thread']:.2e} "
          f"({worst['dimension']}D N={worst['particles']}) .. "
          f"{best['force_loop_pairs_per_second_per_thread']:.2e}",
          "force-pass pairs / force-pass seconds / threads, periodic boxes (sphfmu bench)",
          ">= 1.0e8", worst["force_loop_pairs_per_second_per_thread"] >= 1e8)
    for d in sorted({r["dimension"] for r in rows}):
        rates = [(r["particles"], r["particle_updates_per_second"]) for r in rows
                 if r["dimension"] == d]
        if len(rates) < 2:
            continue
        mid = sorted(x for _, x in rates)[len(rates) // 2]
        spread = max(abs(x / mid - 1.0) for _, x in rates)
        g.add(f"cost linear in N, {d}D",
              ", ".join(f"N={n}: {x:.2e}/s" for n, x in rates),
              "median of the sizes (sphfmu bench)", "every size within +-15 %",
              spread <= 0.15, f"largest deviation {100 * spread:.0f} %")


def mpi_goals(g, table, mpi):
    """2 ranks x 1 thread (mpirun) against 1 rank x 2 threads on the 1e6-particle 3D box."""
    pick = lambda rows: next((r for r in rows or [] if r["dimension"] == 3 and r["particles"] == 1000000), None)
    one, two = pick(table), pick(mpi)
    if not (one and two and two.get("ranks", 1) > 1):
        g.add("MPI: 2 ranks x 1 thread / 1 rank x 2 threads, 3D 1e6", "-", "target/bench-mpi.json",
              "report (docs/scaling.md)", None, "run `make bench` (mpirun) first")
        return
    ratio = two["particle_updates_per_second"] / one["particle_updates_per_second"]
    g.add("MPI: 2 ranks x 1 thread / 1 rank x 2 threads, 3D 1e6", f"{ratio:.2f}x",
          f"{two['particle_updates_per_second']:.3e} / {one['particle_updates_per_second']:.3e} particle-updates/s",
          ">= 1/(1 + halo/owned) (the halo's redundant work alone)",
          ratio >= 1.0 / (1.0 + two["halo_per_owned"]),
          f"{two['bytes_per_step']:.2e} bytes sent per step by rank 0, {100 * two['exchange_share']:.0f} % of its step "
          f"in exchanges, halo/owned {two['halo_per_owned']:.2f}")


def rounds_text(a, b):
    """How many interleaved rounds each side's median is of (tools/bench_peer.py --rounds)."""
    na, nb = len(a.get("rates", [0])), len(b.get("rates", [0]))
    return "" if na == nb == 1 else f", medians of {na} and {nb} rounds"


def peer_goals(g, peer):
    aims = [("standard", "psph", 20.0, "our standard SPH / PySPH PSPH"),
            ("psph", "psph", 10.0, "our PSPH / PySPH PSPH"),
            ("crksph", "crksph", 30.0, "our CRKSPH / PySPH CRKSPH")]
    if not peer:
        for ours, theirs, aim, what in aims:
            g.add(f"Noh 2D: {what}", "-", "target/bench-peer.json", f">= {aim:.0f}x", None,
                  "run tools/bench_peer.sh first (make bench does)")
        return
    mine = {r["scheme"]: r for r in peer if r["code"] == "sphfmu"}
    peers = {r["scheme"]: r for r in peer if r["code"] != "sphfmu"}
    for ours, theirs, aim, what in aims:
        if ours not in mine or theirs not in peers:
            g.add(f"Noh 2D: {what}", "-", "target/bench-peer.json", f">= {aim:.0f}x", None,
                  "not in this peer run")
            continue
        a, b = mine[ours]["updates_per_s"], peers[theirs]["updates_per_s"]
        g.add(f"Noh 2D: {what}", f"{a / b:.1f}x ({a:.2e} / {b:.2e} particle-updates/s)",
              f"{peers[theirs]['code']} in the same run, {peers[theirs]['threads']} threads"
              + rounds_text(mine[ours], peers[theirs]),
              f">= {aim:.0f}x", a / b >= aim)


def sod3d_goals(g, tmp, baselines, model):
    s = run(os.path.join(ROOT, "models", "bench", "sod3d.toml"), os.path.join(tmp, "sod3d"))
    rate = s["particle_updates_per_second"]
    base = baselines["machines"].get(model, {})
    swift = base.get("swift_gadget2_sod3d")
    ours0 = base.get("sod3d")
    lead = baselines["swift_lead_over_baseline"]
    if swift:
        # SWIFT measured on this CPU model (BENCHMARKS.md has the commands); the VM's speed
        # moves from day to day, so the side-by-side ratio of that session is shown as well.
        g.add("3D Sod (models/bench/sod3d.toml): particle-updates/s, 2 threads",
              f"{rate:.3e} = {rate / swift['rate']:.2f}x SWIFT's",
              f"SWIFT Gadget-2 on this CPU: {swift['rate']:.2e} ({swift['date']}; side by side "
              f"that day: {swift['side_by_side']})", f">= {swift['rate']:.2e}",
              rate >= swift["rate"])
    elif ours0:
        target = lead["ratio"] * ours0["rate"]
        g.add("3D Sod (models/bench/sod3d.toml): particle-updates/s, 2 threads",
              f"{rate:.3e} = {rate / ours0['rate']:.2f}x our baseline",
              f"our baseline on this CPU {ours0['rate']:.3e} ({ours0['commit']}); SWIFT's lead "
              f"over it: {lead['ratio']}x ({lead['source']})",
              f">= {lead['ratio']}x = {target:.2e}", rate >= target)
    else:
        g.add("3D Sod (models/bench/sod3d.toml): particle-updates/s, 2 threads", f"{rate:.3e}",
              f"no baseline for CPU '{model}' in tools/bench_baselines.json", "-", None)
    l1 = s["shock_tube"]["l1_density"]
    g.add("3D Sod: L1(rho), 0.5 < x < 1.5", f"{l1:.4f}", "exact Riemann solution (SWIFT Gadget-2: 0.0104)",
          "<= 0.0104", l1 <= 0.0104)
    share = s["phase_seconds"][0] / s["wall_seconds"]
    g.add("3D Sod: neighbour upkeep share of a step", f"{100 * share:.0f} %",
          "list builds, validity checks and the cut of the working list (with the velocity-"
          "gradient sums that ride on it)", "<= 15 %", share <= 0.15,
          f"{s['neighbour_list_builds']} list builds in {s['steps']} steps")


# Interleaved rounds for the goals measured by whole runs here (cost ratios, the tank's
# speed-up); each reads the median round. One run of each moved the Rosswog F1 ratio from 2.02x
# to 2.74x and the tank's speed-up from 1.51x to 1.20x between `make bench` runs with no change
# to those passes, while six interleaved pairs of the F1 cost runs (three with the binary
# before and three after the change of that session) gave 2.08-2.56x (BENCHMARKS.md,
# 2026-12-07, sixth session).
ROUNDS = 3


def median(values):
    ranked = sorted(values)
    return ranked[(len(ranked) - 1) // 2]


def cost_goals(g, tmp):
    presets = preset_defaults()
    for scheme, aim in (("crksph", 3.0), ("rosswog-f1", 2.5)):
        kernel, eta, integrator, cfl = presets[scheme]
        ratios = []
        for k in range(ROUNDS):
            cost = {}
            for name in ("standard", scheme):
                case = box_case(os.path.join(tmp, f"cost-{scheme}-{name}.toml"), name, kernel,
                                eta, integrator, cfl)
                s = run(case, os.path.join(tmp, f"cost-{scheme}-{name}-{k}"))
                cost[name] = 1.0 / s["particle_updates_per_second"]
            ratios.append(cost[scheme] / cost["standard"])
        ratio = median(ratios)
        g.add(f"{scheme} cost per particle-update / standard SPH's", f"{ratio:.2f}x",
              f"2D periodic box of 200^2, both with {kernel} eta {eta}, {integrator}, CFL {cfl}; "
              f"median of {ROUNDS} interleaved pairs",
              f"<= {aim}x",
              ratio <= aim, "pairs: " + ", ".join(f"{r:.2f}x" for r in ratios))


def thread_goals(g, tmp):
    case = os.path.join(ROOT, "models", "closed-tank2d.toml")
    runs = {}
    speedups = []
    for k in range(ROUNDS):
        # the first round's 2-thread runs also serve the determinism checks below
        tags = (("1", 1), ("2a", 2), ("2b", 2)) if k == 0 else ((f"1-{k}", 1), (f"2-{k}", 2))
        for tag, threads in tags:
            out = os.path.join(tmp, f"tank-{tag}")
            runs[tag] = (run(case, out, threads), out)
        one, two = (runs[t][0]["wall_seconds"] for t, _ in tags[:2])
        speedups.append(one / two)
    speedup = median(speedups)
    g.add("closed tank (1,566 particles): speed-up from a second thread", f"{speedup:.2f}x",
          f"the same run on 1 thread; median of {ROUNDS} interleaved pairs", ">= 1.7x",
          speedup >= 1.7, "pairs: " + ", ".join(f"{r:.2f}x" for r in speedups))

    def same(x, y):
        fx = sorted(glob.glob(os.path.join(runs[x][1], "snapshot_*")))
        fy = sorted(glob.glob(os.path.join(runs[y][1], "snapshot_*")))
        return bool(fx) and len(fx) == len(fy) and all(
            filecmp.cmp(a, b, shallow=False) for a, b in zip(fx, fy))

    g.add("deterministic for a thread count", "same bits" if same("2a", "2b") else "differ",
          "two 2-thread closed-tank runs, every snapshot byte for byte", "same bits",
          same("2a", "2b"))
    g.add("independent of the thread count", "same bits" if same("1", "2a") else "differ",
          "1 against 2 threads, closed tank snapshots byte for byte", "(reported)", None
          if not same("1", "2a") else True,
          "" if same("1", "2a") else "sums are split per thread; reported, not a goal")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-runs", action="store_true")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "bench-goals.md"))
    ap.add_argument("--table", default=os.path.join(ROOT, "target", "bench.json"))
    ap.add_argument("--peer", default=os.path.join(ROOT, "target", "bench-peer.json"))
    ap.add_argument("--mpi", default=os.path.join(ROOT, "target", "bench-mpi.json"))
    a = ap.parse_args()
    model = cpu_model()
    baselines = json.load(open(os.path.join(ROOT, "tools", "bench_baselines.json")))
    g = Goals()
    table_goals(g, load_json(a.table))
    mpi_goals(g, load_json(a.table), load_json(a.mpi))
    peer_goals(g, load_json(a.peer))
    if not a.skip_runs:
        with tempfile.TemporaryDirectory() as tmp:
            sod3d_goals(g, tmp, baselines, model)
            cost_goals(g, tmp)
            thread_goals(g, tmp)
    text = (f"Performance goals (tools/bench_goals.py), CPU '{model}', {os.cpu_count()} cores\n\n"
            + g.markdown() + "\n")
    print(text)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    open(a.out, "w").write(text)
    json.dump({"cpu": model, "goals": g.rows}, open(a.out.replace(".md", ".json"), "w"), indent=2)
    print(f"(also written to {a.out})")


if __name__ == "__main__":
    main()
