#!/usr/bin/env python3
"""The verification suite: every claim of models/verify/suite.toml, measured, judged, reported.

    python tools/verify.py [--jobs N] [--only ID[,ID...]] [--suite models/verify/suite.toml]
                           [--out docs/verification] [--work target/verify]

Each claim of the three papers (Rosswog 2015, Abel 2011, Frontiere, Raskin & Owen 2017) is one
entry of the suite. A measured entry names a model, the schemes to run it with, optional
resolutions (`--set` overrides of the case file) and a metric (tools/verify_metrics.py); its
judge compares the figure of one scheme (or a ratio, or a convergence order) with the paper's.
Entries backed by a Rust test run that test and read its printed figure. Entries not built yet
or out of reach on this machine say why. The report goes to docs/verification/README.md with
one PNG per measured claim next to it; the runs stay under target/verify/runs/.

Runs are independent processes: --jobs N runs N at once, each with cores/N threads.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import hashlib
import json
import math
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from verify_metrics import METRICS, parse_kernel_table, summary_value  # noqa: E402
from verify_plots import PLOTS, claim_scheme  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
# SPHFMU_BIN runs the suite with a copy of the binary, so a rebuild meanwhile cannot change it
BIN = Path(os.environ.get("SPHFMU_BIN", ROOT / "target" / "release" / "sphfmu"))
PAPERS = {
    "rosswog": "Rosswog (2015), Boosting the accuracy of SPH (Newtonian part)",
    "rosswog-sr": "Rosswog (2015), Boosting the accuracy of SPH (special-relativistic part)",
    "rpsph": "Abel (2011), rpSPH: a novel smoothed particle hydrodynamics algorithm",
    "crksph": "Frontiere, Raskin & Owen (2017), CRKSPH",
}


@dataclass
class Run:
    """One `sphfmu run` of a model with a scheme and overrides, or one Rust test."""

    model: str
    scheme: str
    sets: tuple[str, ...]
    dir: Path
    summary: dict = field(default_factory=dict)
    error: str | None = None
    seconds: float = 0.0
    kernel_table: dict = field(default_factory=dict)
    # taken finished from an earlier, interrupted invocation (`--reuse`)
    reused: bool = False

    def command(self, threads: int) -> list[str]:
        cmd = [str(BIN), "run", self.model, "--out", str(self.dir), "--quiet", "--threads", str(threads)]
        if self.scheme != "case":
            cmd += ["--scheme", self.scheme]
        for s in self.sets:
            cmd += ["--set", s]
        # every run ends with a CSV snapshot the metrics read (and a VTU for ParaView), unless
        # the claim chose (a time series of many snapshots: CSV only)
        if not any(s.startswith("output.formats=") for s in self.sets):
            cmd += ["--set", 'output.formats=["csv", "vtu"]']
        return cmd

    def is_kernel_table(self) -> bool:
        """A `sphfmu kernels ...` table (the model string is the command's arguments), not a run."""
        return self.model.split()[0] == "kernels"

    def shown(self) -> str:
        """The command as a user would type it (relative paths, no --out)."""
        if self.is_kernel_table():
            return f"sphfmu {self.model}"
        parts = ["sphfmu run", self.model]
        if self.scheme != "case":
            parts += ["--scheme", self.scheme]
        parts += [f"--set '{s}'" for s in self.sets]
        return " ".join(parts)


def run_key(model: str, scheme: str, sets: tuple[str, ...]) -> str:
    h = hashlib.sha1(json.dumps([model, scheme, sets]).encode()).hexdigest()[:8]
    return f"{Path(model).stem}-{scheme}-{h}"


# One hour per run (issue 20: a row that needs more gets a reduced resolution). A run whose time
# step has collapsed crawls for hours instead (rpSPH on
# the triple point reached t = 1.45 of 5 with Δt = 1.3e-9 after 32 min): stop it and say where.
MAX_RUN_SECONDS = float(os.environ.get("SPHFMU_VERIFY_MAX_RUN", 3600))


def progress(run_dir: Path) -> str:
    """Where a stopped run got to: the time and step of its last diagnostics line."""
    try:
        last = (run_dir / "diagnostics.csv").read_text().strip().splitlines()[-1].split(",")
        return f"at t = {float(last[0]):.4g} (step {last[1]}, time step {float(last[2]):.3g})"
    except (OSError, IndexError, ValueError):
        return "with no diagnostics written"


def busy_seconds(run_dirs: list[Path]) -> float:
    """Wall clock during which at least one of these runs was running: the length of the union
    of their [end − seconds, end] intervals, from each command.json ("finished", else the file's
    time). Across resumed invocations (`--reuse`) it is the suite's wall time without the gaps
    between invocations, where one invocation's own clock would cover only its part."""
    spans = []
    for d in run_dirs:
        f = d / "command.json"
        try:
            rec = json.loads(f.read_text())
            end = float(rec.get("finished", f.stat().st_mtime))
            spans.append((end - float(rec["seconds"]), end))
        except (OSError, ValueError, KeyError):
            pass  # never ran, or a record from before "seconds"
    total, reach = 0.0, -math.inf
    for start, end in sorted(spans):
        if end > reach:
            total += end - max(start, reach)
            reach = end
    return total


def execute(run: Run, threads: int, reuse: bool = False) -> Run:
    """Run it, or with `reuse` take the finished run in its directory made by the same command
    and the same binary (command.json records both)."""
    record = {"command": [run.model, run.scheme, list(run.sets)], "binary_mtime": BIN.stat().st_mtime}
    done = run.dir / "command.json"
    old = json.loads(done.read_text()) if reuse and done.exists() else {}
    # a run killed by a signal (the session's end, an OOM kill) was interrupted and has no result
    # to keep; records from before "killed" existed say so as a negative exit status
    killed = old.get("killed", str(old.get("error") or "").startswith("exit -"))
    if (old.get("command") == record["command"] and old.get("binary_mtime") == record["binary_mtime"]
            and not killed):
        run.seconds, run.error, run.reused = old["seconds"], old.get("error"), True
        if not run.error:
            run.summary = json.loads((run.dir / "summary.json").read_text())
        return run
    if run.dir.exists():
        shutil.rmtree(run.dir)
    run.dir.mkdir(parents=True)
    t0 = time.time()
    killed_by = None

    def finished() -> Run:
        # the record --reuse and busy_seconds read
        done.write_text(json.dumps({**record, "seconds": run.seconds, "error": run.error, "finished": time.time(),
                                    "killed": killed_by is not None}))
        return run

    try:
        p = subprocess.run(run.command(threads), cwd=ROOT, capture_output=True, text=True, timeout=MAX_RUN_SECONDS)
    except subprocess.TimeoutExpired:
        run.seconds = time.time() - t0
        run.error = f"stopped after {run.seconds:.0f} s (the suite's limit per run), {progress(run.dir)}"
        return finished()
    run.seconds = time.time() - t0
    (run.dir / "log.txt").write_text(p.stdout + p.stderr)
    if p.returncode < 0:
        killed_by = signal.Signals(-p.returncode).name
        run.error = f"killed by {killed_by} after {run.seconds:.0f} s (interrupted: `--reuse` runs it again)"
    elif p.returncode != 0:
        last = (p.stderr.strip().splitlines() or ["(no message)"])[-1]
        last = re.sub(r"\s*\(snapshots so far kept in [^)]*\)", "", last.removeprefix("sphfmu: "))
        run.error = f"exit {p.returncode}: {last}"
    else:
        run.summary = json.loads((run.dir / "summary.json").read_text())
    return finished()


def execute_test(filt: str, ignored: bool) -> tuple[bool, str, float]:
    # the Makefile's features, so the test binary is the one `make test` already built
    cmd = ["cargo", "test", "--release", "-p", "sphfmu", "--features", "mpi", "--test", "all", "-q", filt, "--", "--nocapture", "--exact"]
    if ignored:
        cmd.append("--ignored")
    t0 = time.time()
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    return p.returncode == 0, p.stdout + p.stderr, time.time() - t0


# ----------------------------------------------------------------------------- judging


def fit_order(ns: list[float], errs: list[float]) -> float:
    """Least-squares slope of −log(err) against log(N): the convergence order."""
    xs = [math.log(n) for n in ns]
    ys = [-math.log(e) for e in errs]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def judges(claim: dict) -> list[dict]:
    """The claim's judges: one `[claim.judge]` table, or several `[[claim.judge]]` that must all
    pass (a claim with two parts, e.g. "30× less dissipation, and convergent")."""
    j = claim.get("judge", [])
    return [j] if isinstance(j, dict) else list(j)


def judge(claim: dict, figures: dict, seconds: dict | None = None) -> tuple[str, str]:
    """(verdict, our figure as text): reproduced when every judge passes. `seconds` holds each
    run's wall time as figures holds its figure (the "cost" judge reads both)."""
    results = [judge_one(claim, j, figures, seconds or {}) for j in judges(claim)]
    verdict = "reproduced" if all(v == "reproduced" for v, _ in results) else "not reproduced"
    return verdict, "; ".join(t for _, t in results)


def error_at_cost(errs: dict, secs: dict) -> tuple[float, float]:
    """Least-squares fit of ln(error) against ln(wall time) over a scheme's resolutions:
    (intercept, slope)."""
    pts = [(math.log(secs[l]), math.log(v)) for l, v in errs.items() if not isinstance(v, str) and v > 0 and secs.get(l, 0) > 0]
    if len(pts) < 2:
        raise ValueError("fewer than two finished resolutions")
    mx, my = sum(p[0] for p in pts) / len(pts), sum(p[1] for p in pts) / len(pts)
    slope = sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)
    return my - slope * mx, slope


def judge_one(claim: dict, j: dict, figures: dict, seconds: dict | None = None) -> tuple[str, str]:
    """(verdict, our figure as text) from figures[scheme][label] (label: a resolution's N or '')."""
    kind = j["kind"]
    metric = claim["run"]["metric"]

    def value(scheme: str, label=None) -> float:
        series = figures[scheme]
        if label is None:
            label = list(series)[-1]  # the finest resolution
        if str(label) not in series:
            raise ValueError(f"{scheme}: no run at N = {label}")
        v = series[str(label)]
        if isinstance(v, str):
            raise ValueError(f"{scheme}: {v}")
        return v

    try:
        if kind == "order":
            series = figures[j["scheme"]]
            bad = [v for v in series.values() if isinstance(v, str)]
            if bad:
                raise ValueError(f"{j['scheme']}: {bad[0]}")
            ns, errs = [float(n) for n in series], list(series.values())
            got = fit_order(ns, errs)
            text = f"{j['scheme']}: order {got:.2f} ({metric} {errs[0]:.3g} → {errs[-1]:.3g}, N {ns[0]:g} → {ns[-1]:g})"
        elif kind == "cost":
            # the two schemes' error-against-wall-time lines compared at one wall time, the
            # geometric middle of the times both ran (CRKSPH §4.3.3's cost-accuracy plot)
            a, b = j["schemes"]
            fa, fb = (error_at_cost(figures[s], (seconds or {}).get(s, {})) for s in (a, b))
            ta = [seconds[a][l] for l in figures[a] if not isinstance(figures[a][l], str)]
            tb = [seconds[b][l] for l in figures[b] if not isinstance(figures[b][l], str)]
            lo, hi = max(min(ta), min(tb)), min(max(ta), max(tb))
            if lo > hi:
                lo, hi = min(ta + tb), max(ta + tb)
            t = math.sqrt(lo * hi)
            ea, eb = (math.exp(f[0] + f[1] * math.log(t)) for f in (fa, fb))
            got = ea / eb
            text = f"{metric} at equal wall time ({t:.3g} s): {a} / {b} = {got:.3g} ({ea:.3g} / {eb:.3g})"
        elif kind == "ratio":
            # `at`: the resolution both are read at (else each scheme's finest), for a claim
            # whose finest resolution only some schemes run (a map at the paper's size)
            a, b = j["schemes"]
            va, vb = value(a, j.get("at")), value(b, j.get("at"))
            got = va / vb
            at = f" at N = {j['at']}" if "at" in j else ""
            text = f"{metric} {a} / {b}{at} = {got:.3g} ({va:.3g} / {vb:.3g})"
        else:
            got = value(j["scheme"], j.get("at"))
            text = f"{j['scheme']}: {metric} = {got:.4g}"
    except (ValueError, KeyError) as e:
        return "not reproduced", f"run failed: {e}"
    lo, hi = j.get("min", -math.inf), j.get("max", math.inf)
    ok = lo <= got <= hi and math.isfinite(got)
    return ("reproduced" if ok else "not reproduced"), text


# ----------------------------------------------------------------------------- plots


def plot_claim(claim: dict, figures: dict, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = claim["run"]
    metric = r["metric"]
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    if "resolutions" in r:
        for scheme, series in figures.items():
            pts = [(float(n), v) for n, v in series.items() if not isinstance(v, str) and v > 0]
            if pts:
                ax.loglog(*zip(*pts), "o-", label=scheme)
        ns = [float(x["n"]) for x in r["resolutions"]]
        oj = next((j for j in judges(claim) if j["kind"] == "order"), {})
        order, scheme = oj.get("min"), oj.get("scheme")
        if scheme in figures and order:
            first = next((v for v in figures[scheme].values() if not isinstance(v, str)), None)
            if first:
                ax.loglog(ns, [first * (n / ns[0]) ** -order for n in ns], "k--", lw=0.8, label=f"N^-{order:g} (paper's order)")
        ax.set_xlabel(r.get("n_label", "N (particles per dimension)"))
        ax.set_ylabel(f"{metric} ({r.get('unit', 'dimensionless')})")
    else:
        names, vals, colours = [], [], []
        for scheme, series in figures.items():
            v = list(series.values())[-1]
            names.append(scheme)
            vals.append(v if not isinstance(v, str) else 0.0)
            colours.append("tab:red" if isinstance(v, str) else "tab:blue")
        ax.bar(range(len(names)), vals, color=colours)
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
        pos = [v for v in vals if v > 0]
        if pos and max(pos) / min(pos) > 100:
            ax.set_yscale("log")
        ax.set_ylabel(f"{metric} ({r.get('unit', 'dimensionless')})")
        ax.set_xlabel(r.get("x_label", "scheme (red: the run failed)"))
        for j in judges(claim):
            for key, colour in (("min", "g"), ("max", "r")):
                lim = j.get(key)
                if lim is not None and j["kind"] == "value" and math.isfinite(lim):
                    ax.axhline(lim, ls="--", color=colour, lw=0.8, label=f"verdict {key} {lim:g}")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    ax.set_title(f"{claim['id']}: {claim['claim'][:70]}", fontsize=8)
    fig.text(0.01, 0.01, "python tools/verify.py --only " + claim["id"], fontsize=6, color="grey")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def plot_test_series(claim: dict, log: str, png: Path) -> bool:
    """A test-backed convergence claim's error against resolution, read from the test's printed
    lists (`[claim.test.series]`: `n`, a regex whose group is the comma-separated resolutions;
    `schemes`, {label: regex of that scheme's errors}; `metric`, `unit`, `order`: the paper's
    order drawn through the first scheme's coarsest point). False when a list is missing."""
    ts = claim["test"]["series"]

    def numbers(pattern: str) -> list[float] | None:
        m = re.search(pattern, log)
        return [float(v) for v in m.group(1).split(",")] if m else None

    ns = numbers(ts["n"])
    figures = {}
    for label, pattern in ts["schemes"].items():
        errs = numbers(pattern)
        if not ns or not errs or len(errs) != len(ns):
            return False
        figures[label] = {f"{n:g}": e for n, e in zip(ns, errs)}
    shown = {
        **claim,
        "run": {"metric": ts["metric"], "unit": ts.get("unit", "dimensionless"), "resolutions": [{"n": n} for n in ns],
                "n_label": ts.get("n_label", "N (particles per dimension)")},
        "judge": {"kind": "order", "scheme": next(iter(ts["schemes"])), "min": ts["order"]},
    }
    plot_claim(shown, figures, png)
    return True


def plot_test_bars(claim: dict, log: str, figure: str, png: Path) -> bool:
    """A test-backed claim's figures as bars, read from the row's figure line, or from the
    whole test output when `source = "log"` (`[claim.test.bars]`: `pattern`, a regex with
    groups `label` and `value`, every match one bar; `metric` and `unit` name the axis).
    False when nothing matches."""
    tb = claim["test"]["bars"]
    text = log if tb.get("source") == "log" else figure
    figures = {m.group("label").strip(): {"": float(m.group("value"))} for m in re.finditer(tb["pattern"], text)}
    if not figures:
        return False
    shown = {"metric": tb["metric"], "unit": tb.get("unit", "dimensionless"), "x_label": tb.get("x_label", "variant")}
    plot_claim({**claim, "run": shown, "judge": []}, figures, png)
    return True


# ----------------------------------------------------------------------------- suite


# What a `from` row takes from the row it names: what makes the runs, not how they are read.
RUN_KEYS = ("model", "schemes", "variants", "resolutions", "set", "n_label")


def load_suite(path: Path) -> dict:
    """The suite with each `[claim.run] from = "ID"` filled in: that claim's runs (RUN_KEYS)
    under this claim's own keys (metric, its arguments, plot, ...), so rows that read other metrics
    of the same runs name those runs once. The runs' keys are the same as if written out."""
    suite = tomllib.loads(path.read_text())
    runs = {c["id"]: c.get("run") for c in suite["claim"]}
    for c in suite["claim"]:
        src = c.get("run", {}).get("from")
        if src is None:
            continue
        base = runs.get(src)
        if base is None or "from" in base:
            raise ValueError(f"{c['id']}: run.from = {src!r} names no claim with a run table of its own")
        own = {k: v for k, v in c["run"].items() if k != "from"}
        shared = {k: json.loads(json.dumps(base[k])) for k in RUN_KEYS if k in base}
        c["run"] = {**shared, **own}
    return suite


def expand(claim: dict, work: Path) -> list[tuple[str, str, Run, dict]]:
    """(scheme or variant label, resolution label, run, metric arguments) of a measured claim."""
    r = claim["run"]
    out = []
    resolutions = r.get("resolutions", [{"n": "", "set": []}])
    for entry in r["schemes"]:
        # a scheme preset's name, or a variant: {label, scheme ("case": the file's own), set}
        args = dict(r.get("metric_args", {}))
        if isinstance(entry, str):
            label, scheme, extra = entry, entry, ()
        else:
            label, scheme, extra = entry["label"], entry.get("scheme", "case"), tuple(entry.get("set", []))
            args.update(entry.get("metric_args", {}))
        for res in resolutions:
            if "schemes" in res and label not in res["schemes"]:
                continue  # a costly resolution run by the schemes it names only
            sets = tuple(r.get("set", [])) + extra + tuple(res["set"])
            key = run_key(r["model"], scheme, sets)
            out.append((label, str(res["n"]), Run(r["model"], scheme, sets, work / "runs" / key), args))
    return out


def expected_seconds(plan: dict, record: Path) -> dict[Path, float]:
    """What each run is expected to take, to start the longest first: its own time when its
    directory holds a finished run (any binary), else its claim's cost in the last report
    shared evenly among the claim's runs. Runs with neither come last."""
    out: dict[Path, float] = {}
    costs: dict[str, float] = {}
    try:
        rows = json.loads(record.read_text())
    except (OSError, ValueError):
        rows = []
    for r in rows:
        try:
            costs[r["id"]] = float(str(r["cost"]).split()[0])
        except (ValueError, IndexError, KeyError):
            pass  # out of reach, or not yet measured
    for cid, entries in plan.items():
        dirs = {run.dir for _, _, run, _ in entries}
        share = costs.get(cid, 0.0) / max(1, len(dirs))
        for d in dirs:
            out[d] = max(out.get(d, 0.0), share)
    for d in list(out):
        try:
            out[d] = float(json.loads((d / "command.json").read_text())["seconds"])
        except (OSError, ValueError, KeyError):
            pass
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--suite", default="models/verify/suite.toml")
    ap.add_argument("--out", default="docs/verification")
    ap.add_argument("--work", default="target/verify")
    ap.add_argument("--jobs", type=int, default=1, help="runs at once (each gets cores/jobs threads)")
    ap.add_argument("--only", default="", help="comma-separated claim ids")
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite README.md and rows.json from rows.json's figures and the suite's current texts and judges, measuring nothing")
    ap.add_argument("--reuse", action="store_true",
                    help="keep finished runs made by the same command and binary (after an interruption)")
    a = ap.parse_args()
    if a.jobs < 1:
        ap.error("--jobs: must be ≥ 1")
    try:
        suite = load_suite(ROOT / a.suite)
    except ValueError as e:
        ap.error(f"--suite: {e}")
    claims = suite["claim"]
    if a.only:
        wanted = set(a.only.split(","))
        unknown = wanted - {c["id"] for c in claims}
        if unknown:
            ap.error(f"--only: no claim {sorted(unknown)} in {a.suite}")
        claims = [c for c in claims if c["id"] in wanted]
    work, out = ROOT / a.work, ROOT / a.out
    if a.report_only:
        rows = refresh_texts(json.loads((out / "rows.json").read_text()), suite)
        (out / "rows.json").write_text(json.dumps(rows, indent=1, default=str) + "\n")
        meta = json.loads((out / "meta.json").read_text())
        # the header describes the run that last measured, partial or full
        last = meta.get("last", {"seconds": meta["seconds"], "only": None})
        write_report(out / "README.md", rows, last["only"], float(last["seconds"]), last.get("work", ""),
                     last_full(meta))
        return 0
    if not BIN.exists():
        print(f"verify: {BIN} is missing; run `make build` first", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.time()

    # every distinct run once, however many claims read it
    runs: dict[Path, Run] = {}
    plan = {}
    for c in claims:
        if "run" in c:
            plan[c["id"]] = expand(c, work)
            for _, _, run, _ in plan[c["id"]]:
                runs.setdefault(run.dir, run)
    cores = os.cpu_count() or 1
    threads = max(1, cores // a.jobs)
    todo = [r for r in runs.values() if not r.is_kernel_table()]
    # longest first (LPT): with the runs in claim order the last hour-long runs started late
    # and ran alone at the end
    expected = expected_seconds(plan, out / "rows.json")
    todo.sort(key=lambda r: -expected.get(r.dir, 0.0))
    print(f"verify: {len(claims)} claims, {len(todo)} runs, {a.jobs} at once with {threads} threads each")
    done = 0
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = [pool.submit(execute, r, threads, a.reuse) for r in todo]
        for f in cf.as_completed(futures):
            r = f.result()
            done += 1
            status = r.error or f"{r.summary.get('steps', '?')} steps"
            print(f"  [{done}/{len(todo)}] {r.shown()}: {r.seconds:.1f} s, {status}", flush=True)
    tables: dict[str, tuple[dict, float]] = {}
    for r in (r for r in runs.values() if r.is_kernel_table()):
        if r.model not in tables:
            t0 = time.time()
            text = subprocess.run([str(BIN), *r.model.split()], capture_output=True, text=True, check=True).stdout
            tables[r.model] = parse_kernel_table(text), time.time() - t0
        r.kernel_table, r.seconds = tables[r.model]

    rows = []
    for c in claims:
        row = {k: c.get(k, "") for k in ("id", "paper", "number", "claim", "paper_value", "note", "reduced")}
        status = c.get("status", "measured")
        if status in ("not-built", "out-of-reach"):
            row.update(verdict="out of reach" if status == "out-of-reach" else "not built yet", ours=c["why"], command="", cost=c.get("cost", ""))
        elif "test" in c:
            t = c["test"]
            ok, log, secs = execute_test(t["filter"], t.get("ignored", False))
            m = re.search(t["figure"], log)
            figure = m.group(0) if m else "(figure line not found in the test output)"
            row.update(
                verdict="reproduced" if ok and m else "not reproduced",
                ours=figure + ("" if ok else " — the test FAILED"),
                command=f"cargo test --release -p sphfmu --features mpi --test all {t['filter']} -- --exact --nocapture"
                + (" --ignored" if t.get("ignored") else ""),
                cost=f"{secs:.0f} s",
            )
            (work / "tests").mkdir(parents=True, exist_ok=True)
            (work / "tests" / f"{c['id']}.log").write_text(log)
            png = out / f"{c['id']}.png"
            if ("series" in t and plot_test_series(c, log, png)) or ("bars" in t and plot_test_bars(c, log, figure, png)):
                row["png"] = png.name
        else:
            figures: dict[str, dict[str, float | str]] = {}
            seconds: dict[str, dict[str, float]] = {}
            cost, costed = 0.0, set()
            for scheme, label, run, args in plan[c["id"]]:
                run = runs[run.dir]
                if run.dir not in costed:  # a run (or table) that several labels read costs once
                    costed.add(run.dir)
                    cost += run.seconds
                m = c["run"]["metric"]
                if run.error and not getattr(METRICS.get(m), "on_failure", False):
                    val: float | str = run.error
                else:
                    try:
                        m = c["run"]["metric"]
                        val = METRICS[m](run, args) if m in METRICS else summary_value(run.summary, m)
                    except (KeyError, ValueError) as e:
                        val = f"metric: {e}"
                figures.setdefault(scheme, {})[label] = val
                seconds.setdefault(scheme, {})[label] = run.seconds
            verdict, ours = judge(c, figures, seconds) if "judge" in c else ("measured", "")
            png = out / f"{c['id']}.png"
            plot_claim(c, figures, png)
            judged_label = claim_scheme(c)
            profile = None
            if "plot" in c["run"]:
                # the claim's own figure (growth curves, profiles, maps) from its runs
                finished = [(s_, l_, runs[r_.dir], a_) for s_, l_, r_, a_ in plan[c["id"]] if not runs[r_.dir].error]
                profile = out / f"{c['id']}-profile.png"
                try:
                    PLOTS[c["run"]["plot"]](c, finished, profile)
                except (KeyError, ValueError, IndexError) as e:
                    print(f"  {c['id']}: plot {c['run']['plot']} failed: {e}", file=sys.stderr)
                    profile = None
            else:
                for scheme, label, run, _ in plan[c["id"]]:
                    if scheme == judged_label and (run.dir / "profile.png").exists():
                        profile = run.dir / "profile.png"  # the finest resolution, last
                if profile:
                    shutil.copy(profile, out / f"{c['id']}-profile.png")
            # the command of the judged scheme's finest run (the first scheme's for a ratio), or
            # of its run at the resolution the judge reads (`at`)
            at = next((str(j["at"]) for j in judges(c) if "at" in j), None)
            first = next((run for s_, l_, run, _ in reversed(plan[c["id"]])
                          if s_ == judged_label and at in (None, l_)), plan[c["id"]][-1][2])
            row.update(
                verdict=verdict,
                ours=ours,
                command=first.shown(),
                cost=f"{cost:.0f} s",
                figures=figures,
                png=png.name,
                profile=(out / f"{c['id']}-profile.png").name if profile else None,
                metric=c["run"]["metric"],
                lower_is_better=c["run"].get("lower_is_better", True),
                ideal=c["run"].get("ideal"),
            )
        rows.append(row)
        print(f"  {c['id']}: {row['verdict']} — {row['ours']}")

    # --only re-measures some claims: the other rows come from the last full report's record
    record = out / "rows.json"
    if a.only and record.exists():
        fresh = {r["id"]: r for r in rows}
        old = json.loads(record.read_text())
        order = [c["id"] for c in suite["claim"]]
        merged = {r["id"]: r for r in old if r["id"] in order}
        merged.update(fresh)
        rows = refresh_texts([merged[i] for i in order if i in merged], suite)
    record.write_text(json.dumps(rows, indent=1, default=str) + "\n")
    elapsed = time.time() - t_start
    # with --reuse the wall clock covers only this invocation: say so, with the sum of the runs'
    # own times (each on `threads` threads) as the measure of the whole suite's work
    measured = [r for r in runs.values() if not r.is_kernel_table()]
    work_note = (f"{sum(r.reused for r in measured)} of {len(measured)} runs were finished by earlier, "
                 f"interrupted invocations with the same binary (`--reuse`); all {len(measured)} runs "
                 f"took {sum(r.seconds for r in measured) / 3600:.1f} h together, {a.jobs} at once, "
                 f"and kept the machine busy for {busy_seconds(sorted({r.dir for r in measured})) / 3600:.1f} h "
                 f"of wall clock across the invocations"
                 if any(r.reused for r in measured) else "")
    meta_path = out / "meta.json"
    meta = record_run(json.loads(meta_path.read_text()) if meta_path.exists() else {}, a.only, elapsed, work_note)
    write_report(out / "README.md", rows, a.only, elapsed, work_note, last_full(meta))
    meta_path.write_text(json.dumps(meta) + "\n")
    print(f"verify: report {out / 'README.md'} ({time.time() - t_start:.0f} s)")
    return 0


def refresh_texts(rows: list[dict], suite: dict) -> list[dict]:
    """Rows kept from an earlier measurement with the suite's current texts (claims, notes),
    which may have changed since."""
    texts = {c["id"]: c for c in suite["claim"]}
    for r in rows:
        if r["id"] in texts:
            # a key the suite no longer has (a row no longer reduced) goes from the row too
            for k in ("claim", "paper_value", "note", "reduced"):
                r[k] = texts[r["id"]].get(k, "")
        if "run" in texts.get(r["id"], {}):
            c = texts[r["id"]]
            r["ideal"] = c["run"].get("ideal")
            # judging is a function of the stored figures, so a judge changed in the suite
            # takes effect without a rerun; the cost judge also reads run times, not stored
            if r.get("figures") and not any(j["kind"] == "cost" for j in judges(c)):
                r["verdict"], r["ours"] = judge(c, r["figures"]) if judges(c) else ("measured", "")
    return rows


def cell(text: str) -> str:
    """Text for a markdown table cell: a bar (|v|) would end the cell."""
    return str(text).replace("|", "\\|").replace("\n", " ")


def fmt(v) -> str:
    if isinstance(v, str):
        return "failed: " + v.split(": ", 1)[-1][:60]
    return f"{v:.3g}"


def record_run(meta: dict, only: str | None, seconds: float, work_note: str) -> dict:
    """meta.json after a run. "seconds" and "full": the last full run's wall time and work note,
    which a partial run's header repeats; "last": the run the header describes, which
    --report-only repeats."""
    if not only:
        meta["seconds"] = seconds
        meta["full"] = {"seconds": seconds, "work": work_note}
    elif last_full(meta) is not None:
        meta["full"] = last_full(meta)  # read before "last" no longer describes it
    meta["last"] = {"seconds": seconds, "only": only, "work": work_note}
    return meta


def last_full(meta: dict) -> dict | None:
    """The last full run's wall time and work note from meta.json; records written before "full"
    existed have them as "seconds" and, when the last run was full, as "last"."""
    if "full" in meta:
        return meta["full"]
    if "seconds" not in meta:
        return None
    last = meta.get("last", {})
    return {"seconds": meta["seconds"], "work": "" if last.get("only") else last.get("work", "")}


def wall_time_sentence(only: str | None, seconds: float, work_note: str, full: dict | None) -> str:
    """The header's wall time: of this run; after a partial run (`--only`), of the last full run
    too, since the other rows come from it."""
    def timed(secs: float, note: str) -> str:
        return f"{secs / 60:.1f} min" + (f" ({note})" if note else "")
    if not only:
        return f"Wall time of this run: {timed(seconds, work_note)}."
    text = f"Re-measured by the last run: {only}, in {timed(seconds, work_note)}; the other rows are kept in rows.json"
    if full:
        text += f" from the last full run, whose wall time was {timed(float(full['seconds']), full.get('work', ''))}"
    return text + "."


def write_report(path: Path, rows: list[dict], only: str | None, seconds: float, work_note: str = "",
                 full: dict | None = None) -> None:
    cpu = ""
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        cpu = platform.processor()
    counts = {}
    for r in rows:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    o = [
        "# Verification report",
        "",
        "Generated by `make verify` (`python tools/verify.py --jobs 2`, suite `models/verify/suite.toml`);",
        "do not edit by hand, rerun it. Every figure below comes from the command in its row.",
        f"Machine: {cpu}, {os.cpu_count()} cores. " + wall_time_sentence(only, seconds, work_note, full)
        + " The cost column is each claim's own run time.",
        "",
        "Verdicts: " + ", ".join(f"{v} {n}" for v, n in sorted(counts.items())) + ".",
        "**reproduced**: our figure meets the paper's claim by the criterion in the suite file;",
        "**not reproduced**: it does not (the note says what was measured about why);",
        "**out of reach**: needs what this machine or code does not have (cost or reason given);",
        "**not built yet**: no model or measurement yet. Claims marked *reduced* run below the paper's resolution.",
        "",
    ]
    for paper, title in PAPERS.items():
        sel = [r for r in rows if r["paper"] == paper]
        if not sel:
            continue
        o += [f"## {title}", "", "| # | claim | paper | ours | verdict | command | cost |", "|---|---|---|---|---|---|---|"]
        for r in sel:
            claim = cell(r["claim"]) + (" *(reduced)*" if r.get("reduced") else "")
            ours = cell(r["ours"]) + (f" ([plot]({r['png']}))" if r.get("png") else "")
            cmd = f"`{cell(r['command'])}`" if r["command"] else ""
            o.append(f"| {r['number']} | {claim} | {cell(r['paper_value'])} | {ours} | **{r['verdict']}** | {cmd} | {r['cost']} |")
        o.append("")
        for r in sel:
            if r.get("figures") and len(r["figures"]) > 1 or r.get("note") or r.get("profile"):
                o.append(f"**{r['id']}** ({cell(r['claim'])})")
                o.append("")
                if r.get("note"):
                    o += [r["note"].strip(), ""]
                if r.get("figures"):
                    # every resolution any scheme ran (a costly one may be run by some only)
                    labels = list(dict.fromkeys(l for series in r["figures"].values() for l in series))
                    head = [f"N = {l}" if l else r["metric"] for l in labels]
                    o.append("| scheme | " + " | ".join(head) + " |")
                    o.append("|---|" + "---|" * len(head))
                    for s, series in r["figures"].items():
                        o.append(f"| {cell(s)} | " + " | ".join(cell(fmt(series[l])) if l in series else "—" for l in labels) + " |")
                    o.append("")
                if r.get("profile"):
                    o += [f"![{r['id']} profile]({r['profile']})", ""]
    o += ranking(rows)
    path.write_text("\n".join(o) + "\n")


def ranking(rows: list[dict]) -> list[str]:
    """One line per measured test with several schemes: the schemes from best to worst."""
    o = ["## Schemes ranked per test", "",
         "Best first by the test's metric at the finest resolution all schemes ran (ratios to an exact value: closest to 1 first); failed runs last.", "",
         "| test | metric | ranking |", "|---|---|---|"]
    for r in rows:
        f = r.get("figures")
        if not f or len(f) < 2:
            continue
        # the finest resolution every scheme ran (a costly one may be run by some only)
        common = [l for l in next(iter(f.values())) if all(l in series for series in f.values())]
        last = {s: series[common[-1]] if common else list(series.values())[-1] for s, series in f.items()}
        ok = [(v, s) for s, v in last.items() if not isinstance(v, str) and math.isfinite(v)]
        ideal = r.get("ideal")
        if ideal is not None:  # a ratio to the exact value: closest to it first
            ok.sort(key=lambda e: abs(e[0] - ideal))
        else:
            ok.sort(reverse=not r.get("lower_is_better", True))
        failed = [s for s, v in last.items() if isinstance(v, str)]
        text = " > ".join(f"{s} ({v:.3g})" for v, s in ok) + "".join(f" > {s} (failed)" for s in failed)
        o.append(f"| {r['id']} | {r['metric']} | {text} |")
    return o + [""]


if __name__ == "__main__":
    sys.exit(main())
