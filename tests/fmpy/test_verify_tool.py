"""tools/verify.py, the verification suite's runner: its judges on made-up figures, and every
measured entry of models/verify/suite.toml naming a model that `sphfmu check` accepts with the
entry's own overrides (so `make verify` cannot fail on a typo an hour in)."""
import math
import re
import subprocess
import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT / "tools"))
import verify  # noqa: E402

BIN = str(ROOT / "target" / "release" / "sphfmu")


def scheme_presets():
    """The preset names the binary lists under "Schemes and presets" in `sphfmu run --help`, so a
    new preset is accepted here without a second list to keep."""
    text = subprocess.run([BIN, "run", "--help"], capture_output=True, text=True, check=True).stdout
    section = text.split("Schemes and presets", 1)[1].split("signal_velocity", 1)[0]
    names = {m.group(1) for m in re.finditer(r"^  ([a-z][a-z0-9-]+)\s", section, re.M)}
    assert {"standard", "rosswog-f1", "crksph", "psph"} <= names, names
    return names


def test_order_fit_recovers_a_power_law():
    ns = [32, 64, 128]
    assert math.isclose(verify.fit_order(ns, [3.0 * n**-1.5 for n in ns]), 1.5, rel_tol=1e-12)


def claim(kind, **judge):
    return {"run": {"metric": "m"}, "judge": {"kind": kind, **judge}}


def test_judges_decide_against_their_bounds():
    figures = {"a": {"32": 0.1, "64": 0.05}, "b": {"64": 0.2}, "c": {"": "exit 3: unstable"}}
    assert verify.judge(claim("order", scheme="a", min=0.9), figures)[0] == "reproduced"
    assert verify.judge(claim("order", scheme="a", min=1.1), figures)[0] == "not reproduced"
    # a value is the finest resolution's
    assert verify.judge(claim("value", scheme="a", max=0.06), figures)[0] == "reproduced"
    assert verify.judge(claim("ratio", schemes=["b", "a"], min=3.9, max=4.1), figures)[0] == "reproduced"
    # `at` reads both at one resolution, not each scheme's finest
    finer = {"a": {"64": 0.05, "128": 0.01}, "b": {"64": 0.2}}
    verdict, text = verify.judge(claim("ratio", schemes=["b", "a"], at="64", min=3.9, max=4.1), finer)
    assert verdict == "reproduced" and "at N = 64" in text, text
    assert verify.judge(claim("ratio", schemes=["b", "a"], min=3.9, max=4.1), finer)[0] == "not reproduced"
    verdict, text = verify.judge(claim("ratio", schemes=["b", "a"], at="32", min=3.9), finer)
    assert verdict == "not reproduced" and "no run at N = 32" in text, text
    # several judges: reproduced only when every one passes
    both = {"run": {"metric": "m"}, "judge": [{"kind": "value", "scheme": "a", "max": 0.06},
                                              {"kind": "order", "scheme": "a", "min": 1.1}]}
    verdict, text = verify.judge(both, figures)
    assert verdict == "not reproduced" and "order 1.00" in text, text
    both["judge"][1]["min"] = 0.9
    assert verify.judge(both, figures)[0] == "reproduced"
    # cost: two error-against-wall-time lines compared at one wall time; b costs 4x a for the
    # same error (err = 1/t for a, 4/t for b), so at equal time b's error is 4x a's
    figs = {"a": {"1": 1.0, "2": 0.25}, "b": {"1": 4.0, "2": 1.0}}
    secs = {"a": {"1": 1.0, "2": 4.0}, "b": {"1": 1.0, "2": 4.0}}
    cost = {"run": {"metric": "m"}, "judge": {"kind": "cost", "schemes": ["b", "a"], "min": 3.9, "max": 4.1}}
    verdict, text = verify.judge(cost, figs, secs)
    assert verdict == "reproduced", text
    verdict, text = verify.judge(claim("value", scheme="c", max=1.0), figures)
    assert verdict == "not reproduced" and "unstable" in text


def test_velocity_divergence_is_exact_for_a_linear_flow():
    """The ∇·v of the blast maps (verify_metrics.velocity_divergence) on scattered particles in
    v = A x + c: trace A at every particle, edges included (measured 2.4e-15 off)."""
    from verify_metrics import velocity_divergence
    import numpy as np

    rng = np.random.default_rng(1)
    n = 4000
    x, y = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    s = {"x": x, "y": y, "vx": 0.3 * x + 0.7 * y + 0.1, "vy": -0.2 * x + 0.5 * y,
         "h": np.full(n, 0.06), "m": np.full(n, 4 / n), "rho": np.ones(n)}
    assert np.abs(velocity_divergence(s) - 0.8).max() < 1e-12


def test_every_measured_entry_names_a_valid_case():
    suite = verify.load_suite(ROOT / "models" / "verify" / "suite.toml")
    ids = [c["id"] for c in suite["claim"]]
    assert len(ids) == len(set(ids)), "claim ids repeat"
    checked = 0
    presets = scheme_presets()
    for c in suite["claim"]:
        assert c["paper"] in verify.PAPERS, c["id"]
        status = c.get("status", "measured")
        if status != "measured":
            assert c.get("why"), f"{c['id']}: says {status} without why"
            continue
        assert "run" in c or "test" in c, c["id"]
        if "run" not in c:
            continue
        metric = c["run"]["metric"]
        assert metric in verify.METRICS or "." in metric or metric in ("vortex_l1", "wall_seconds"), f"{c['id']}: metric {metric}"
        assert c["run"].get("plot", "shear_flow") in verify.PLOTS, f"{c['id']}: plot {c['run']['plot']}"
        if verify.Run(c["run"]["model"], "case", (), ROOT).is_kernel_table():
            continue  # a `sphfmu kernels` table, not a case file
        for _, _, run, _ in verify.expand(c, ROOT / "target" / "verify-check"):
            cmd = [BIN, "check", run.model] + [a for s in run.sets for a in ("--set", s)]
            if run.scheme != "case":
                assert run.scheme in presets, f"{c['id']}: scheme {run.scheme} is not a preset of `sphfmu run --help`"
                cmd += ["--scheme", run.scheme]
            r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
            assert r.returncode == 0, f"{c['id']}: {' '.join(cmd)}: {r.stderr}"
            checked += 1
    assert checked > 20


def test_report_only_repeats_the_header_of_the_run_that_last_measured(tmp_path):
    """A partial run (--only) names its claims in the report's header, and --report-only, which
    rewrites the report from rows.json, keeps that header instead of the last full run's."""
    out = tmp_path / "docs"
    out.mkdir()
    (out / "rows.json").write_text("[]\n")
    (out / "meta.json").write_text('{"seconds": 3504, "last": {"seconds": 742, "only": "rosswog-5"}}\n')
    argv = sys.argv
    sys.argv = ["verify.py", "--report-only", "--out", str(out)]
    try:
        assert verify.main() == 0
    finally:
        sys.argv = argv
    text = (out / "README.md").read_text()
    assert ("Re-measured by the last run: rosswog-5, in 12.4 min; the other rows are kept in rows.json "
            "from the last full run, whose wall time was 58.4 min.") in text, text[:600]


def test_a_from_row_takes_the_named_rows_runs_and_keeps_its_own_reading(tmp_path):
    base = """[[claim]]
id = "a"
[claim.run]
model = "m.toml"
schemes = ["s1", "s2"]
resolutions = [{ n = 10, set = ["x=1"] }]
metric = "m1"
[claim.run.metric_args]
k = 1
[[claim]]
id = "b"
[claim.run]
from = "%s"
metric = "m2"
"""
    path = tmp_path / "suite.toml"
    path.write_text(base % "a")
    b = verify.load_suite(path)["claim"][1]["run"]
    assert b == {"model": "m.toml", "schemes": ["s1", "s2"], "resolutions": [{"n": 10, "set": ["x=1"]}],
                 "metric": "m2"}  # a's metric and its arguments stay a's
    # the runs are the same ones: same keys for the work folder
    a = verify.load_suite(path)["claim"][0]
    assert [r.dir for _, _, r, _ in verify.expand(a, tmp_path)] == \
        [r.dir for _, _, r, _ in verify.expand({"id": "b", "run": b}, tmp_path)]
    path.write_text(base % "c")
    try:
        verify.load_suite(path)
    except ValueError as e:
        assert "run.from = 'c' names no claim" in str(e)
    else:
        raise AssertionError("an unknown run.from must be refused")


def test_report_only_judges_stored_figures_by_the_suites_current_judge(tmp_path):
    """A judge added or changed in the suite applies to the figures rows.json keeps, without a
    rerun: a row measured without a judge gets its verdict, and one the new bound fails is
    not reproduced."""
    suite = tmp_path / "suite.toml"
    claim = """[[claim]]
id = "{id}"
paper = "crksph"
number = "{number}"
claim = "F4 dissipates at least {bound} times as much"
paper_value = "more"
[claim.run]
model = "m.toml"
schemes = ["f1", "f4"]
metric = "l1"
[claim.judge]
kind = "ratio"
schemes = ["f4", "f1"]
min = {bound}
"""
    suite.write_text("\n".join(claim.format(id=i, number=n, bound=b)
                               for i, n, b in (("pass", "1", 1.2), ("fail", "2", 3.0))))
    out = tmp_path / "docs"
    out.mkdir()
    figures = {"f1": {"": 0.01}, "f4": {"": 0.02}}
    rows = [{"id": i, "paper": "crksph", "number": n, "claim": "", "paper_value": "", "note": "",
             "reduced": "", "verdict": "measured", "ours": "", "command": "", "cost": "1 s",
             "figures": figures, "metric": "l1"} for i, n in (("pass", "1"), ("fail", "2"))]
    (out / "rows.json").write_text(verify.json.dumps(rows))
    (out / "meta.json").write_text('{"seconds": 60}\n')
    argv = sys.argv
    sys.argv = ["verify.py", "--report-only", "--suite", str(suite), "--out", str(out)]
    try:
        assert verify.main() == 0
    finally:
        sys.argv = argv
    got = {r["id"]: r for r in verify.json.loads((out / "rows.json").read_text())}
    assert got["pass"]["verdict"] == "reproduced", got["pass"]
    assert got["fail"]["verdict"] == "not reproduced", got["fail"]
    assert "= 2" in got["pass"]["ours"], got["pass"]["ours"]
    assert "**not reproduced**" in (out / "README.md").read_text()


def test_runs_start_longest_first_by_their_last_cost(tmp_path):
    """The runner's order: a run's own recorded time when its folder has one, else its claim's
    last cost shared among the claim's runs."""
    claims = [
        {"id": "cheap", "run": {"model": "a.toml", "schemes": ["s1", "s2"], "metric": "m"}},
        {"id": "dear", "run": {"model": "b.toml", "schemes": ["s1", "s2"], "metric": "m"}},
    ]
    plan = {c["id"]: verify.expand(c, tmp_path) for c in claims}
    record = tmp_path / "rows.json"
    record.write_text(verify.json.dumps([{"id": "cheap", "cost": "10 s"}, {"id": "dear", "cost": "1000 s"},
                                         {"id": "out", "cost": ""}]))
    timed = plan["cheap"][1][2].dir
    timed.mkdir(parents=True)
    (timed / "command.json").write_text('{"seconds": 2000.0}')
    expected = verify.expected_seconds(plan, record)
    assert expected[plan["dear"][0][2].dir] == 500.0
    assert expected[plan["cheap"][0][2].dir] == 5.0
    assert expected[timed] == 2000.0


def test_busy_wall_clock_is_the_union_of_the_runs_intervals(tmp_path):
    """The suite's wall time across resumed invocations: overlapping runs count once, the gap
    between two invocations not at all, and a folder without a record adds nothing. A record
    without "finished" (written before it existed) ends at its file's time."""
    def record(name, seconds, finished=None):
        d = tmp_path / name
        d.mkdir()
        rec = {"seconds": seconds} | ({"finished": finished} if finished is not None else {})
        (d / "command.json").write_text(verify.json.dumps(rec))
        return d

    # first invocation: [0, 100] and [50, 120] side by side; the second, after a gap: [1000, 1030]
    dirs = [record("a", 100.0, 100.0), record("b", 70.0, 120.0), record("c", 30.0, 1030.0)]
    (tmp_path / "never").mkdir()
    assert verify.busy_seconds(dirs + [tmp_path / "never"]) == 150.0
    # nested inside another run's interval: nothing more
    assert verify.busy_seconds(dirs + [record("d", 10.0, 110.0)]) == 150.0
    old = record("e", 5.0)
    mtime = old.joinpath("command.json").stat().st_mtime
    assert abs(verify.busy_seconds([old]) - 5.0) < 1e-9
    assert abs(verify.busy_seconds([old, record("f", 5.0, mtime - 2.0)]) - 7.0) < 1e-6


def test_reuse_keeps_results_and_reruns_runs_killed_by_a_signal(tmp_path, monkeypatch):
    """`--reuse` resumes an interrupted suite: a run that ended, even with the scheme's own
    error, is kept; one killed by a signal (the session's end killed a noise-box run with
    SIGKILL, and the report showed "exit -9: (no message)" as its result) is run again."""
    fake = tmp_path / "sphfmu"
    # a stand-in binary: writes the summary the runner reads, or dies by SIGKILL when told to
    fake.write_text('#!/bin/sh\n[ -e "$KILL_ME" ] && kill -9 $$\n'
                    'while [ "$1" != "--out" ]; do shift; done\necho \'{"steps": 7}\' > "$2/summary.json"\n')
    fake.chmod(0o755)
    monkeypatch.setattr(verify, "BIN", fake)

    def run(name):
        return verify.Run(model="m.toml", scheme="case", sets=(), dir=tmp_path / name)

    def record(name, error, **extra):
        d = tmp_path / name
        d.mkdir()
        rec = {"command": ["m.toml", "case", []], "binary_mtime": fake.stat().st_mtime,
               "seconds": 19.5, "error": error, **extra}
        (d / "command.json").write_text(verify.json.dumps(rec))

    record("failed", "exit 3: unstable")
    kept = verify.execute(run("failed"), 1, reuse=True)
    assert kept.reused and kept.error == "exit 3: unstable"
    record("killed-old", "exit -9: (no message)")
    again = verify.execute(run("killed-old"), 1, reuse=True)
    assert not again.reused and again.error is None and again.summary == {"steps": 7}
    record("killed-new", "killed by SIGKILL after 20 s", killed=True)
    assert not verify.execute(run("killed-new"), 1, reuse=True).reused

    monkeypatch.setenv("KILL_ME", str(fake))
    dead = verify.execute(run("dies"), 1)
    assert dead.error.startswith("killed by SIGKILL"), dead.error
    assert verify.json.loads((tmp_path / "dies" / "command.json").read_text())["killed"] is True
    monkeypatch.delenv("KILL_ME")
    assert verify.execute(run("dies"), 1, reuse=True).error is None


def test_a_partial_run_keeps_the_full_runs_wall_time_in_the_header():
    """After `--only`, the header still gives the last full run's wall time and work note (the
    other rows come from it), read from meta.json as written before and after "full" existed."""
    note = "262 of 356 runs were finished by earlier, interrupted invocations"
    old_meta = {"seconds": 1028.8, "last": {"seconds": 1028.8, "only": "", "work": note}}
    full = verify.last_full(old_meta)
    assert full == {"seconds": 1028.8, "work": note}
    assert verify.last_full({"seconds": 60.0, "last": {"seconds": 5.0, "only": "a", "work": ""}})["work"] == ""
    assert verify.last_full({}) is None
    whole = verify.wall_time_sentence("", 1028.8, note, full)
    assert whole == f"Wall time of this run: 17.1 min ({note})."
    part = verify.wall_time_sentence("rosswog-6", 66.0, "", full)
    assert part.startswith("Re-measured by the last run: rosswog-6, in 1.1 min;"), part
    assert f"whose wall time was 17.1 min ({note})." in part
    # a partial run after a full one written before "full" existed keeps the full one's note
    meta = verify.record_run(dict(old_meta), "rosswog-6", 28.0, "")
    assert verify.last_full(meta) == full and meta["last"]["only"] == "rosswog-6"
    assert verify.last_full(verify.record_run(meta, "rosswog-5", 9.0, "")) == full
    assert verify.last_full(verify.record_run(meta, "", 99.0, "w")) == {"seconds": 99.0, "work": "w"}
