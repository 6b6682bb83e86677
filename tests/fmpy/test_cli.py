"""The CLI as a user drives it: a Sod run checked against an independent exact solution
(PyPI sodshock), VTU snapshots read back by meshio, and bad input rejected with exit code 2."""
import csv
import pathlib
import subprocess
import json

import meshio
import numpy as np
import pytest

from conftest import ROOT, run


@pytest.fixture(scope="module")
def sod_run(sphfmu_bin, models, tmp_path_factory):
    out = tmp_path_factory.mktemp("sod")
    r = run([sphfmu_bin, "run", str(models / "sod.toml"), "--out", str(out), "--quiet"])
    assert r.returncode == 0, r.stderr
    return out, r.stdout


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def test_sod_against_sodshock(sod_run):
    sodshock = pytest.importorskip("sodshock")
    out, _ = sod_run
    summary = json.loads((out / "summary.json").read_text())
    final = sorted(out.glob("snapshot_*.csv"))[-1]
    p = read_csv(final)
    t = summary["time"]
    assert abs(t - 0.15) < 1e-12
    _, _, values = sodshock.solve(
        left_state=(1.0, 1.0, 0.0), right_state=(0.1, 0.125, 0.0),
        geometry=(-0.5, 0.5, 0.0), t=t, gamma=1.4, npts=20001)
    rho_exact = np.interp(p["x"], values["x"], values["rho"])
    l1 = np.mean(np.abs(p["rho"] - rho_exact))
    # The CLI's own verification (Rust Riemann solver) must agree with the independent one;
    # interpolation on the 20001-point sodshock grid differs by < 1e-4 near the jumps.
    assert abs(l1 - summary["shock_tube"]["l1_density"]) < 1e-4, (l1, summary["shock_tube"])
    assert l1 <= 3.0e-3


def test_vtu_snapshots_open_in_meshio(sod_run):
    out, _ = sod_run
    vtus = sorted(out.glob("snapshot_*.vtu"))
    assert len(vtus) == 4  # t = 0, 0.05, 0.10, 0.15
    m = meshio.read(vtus[-1])
    assert m.points.shape == (720, 3)
    for field in ("density", "pressure", "velocity", "internal_energy", "smoothing_length", "mass"):
        assert field in m.point_data, field
    csvp = read_csv(sorted(out.glob("snapshot_*.csv"))[-1])
    assert np.allclose(m.point_data["density"], csvp["rho"], rtol=1e-12)
    pvd = (out / "snapshots.pvd").read_text()
    assert pvd.count("<DataSet") == 4


def test_diagnostics_series_conserves_mass_and_energy(sod_run):
    out, _ = sod_run
    d = read_csv(out / "diagnostics.csv")
    assert np.all(d["mass"] == d["mass"][0])
    drift = abs(d["total"][-1] - d["total"][0]) / d["total"][0]
    assert drift < 1e-5  # measured 1.3e-6 with mirror walls (leapfrog)
    assert np.all(np.diff(d["time"]) >= 0)


def test_bad_case_exits_2_with_one_line(sphfmu_bin, models, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((models / "sod.toml").read_text().replace("eta = 1.2", "eta = -3"))
    r = run([sphfmu_bin, "check", str(bad)])
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1
    assert "kernel.eta" in r.stderr and "[0.5, 5]" in r.stderr


MODELS = sorted(p.name for p in (ROOT / "models").glob("*.toml"))


@pytest.mark.parametrize("case", MODELS)
def test_every_model_builds(sphfmu_bin, models, case):
    # generate the particles and evaluate the initial state, as `run` would
    r = run([sphfmu_bin, "check", "--build", str(models / case)])
    assert r.returncode == 0, r.stderr
    assert "particles" in r.stdout


def test_run_help_lists_the_presets(sphfmu_bin):
    r = run([sphfmu_bin, "run", "--help"])
    assert r.returncode == 0
    for preset in ("standard", "rpsph", "rosswog-f1", "rosswog-f2", "rosswog-f3", "rosswog-f4"):
        assert preset in r.stdout, preset


@pytest.mark.parametrize("args, needle", [
    (["--case", "no-such-case.toml"], "no-such-case.toml: cannot read"),
    (["--case", "models/slosh2d.toml", "--mode", "off"], "--mode: must be peer or client"),
    (["--case", "models/slosh2d.toml", "--mode", "router"], "zenoh.mode: must be off, peer or client"),
    (["--case", "models/slosh2d.toml", "--listen", "127.0.0.1:7447"], "zenoh.listen: each endpoint must read <protocol>/<address>"),
    (["--case", "models/slosh2d.toml", "--prefix", "a/*/b"], "zenoh.prefix: must be a zenoh key without wildcards"),
    (["--case", "models/slosh2d.toml", "--staleness=-1"], "zenoh.staleness: must be a finite number of seconds ≥ 0"),
    (["--case", "models/slosh2d.toml", "--set", "resolution=50"], "--set resolution: must be in [0.1, 10], got 50"),
    (["--case", "models/slosh2d.toml", "--set", "tank.force=1"], "--set tank.force: is not a parameter or input"),
    (["--case", "models/slosh2d.toml", "--set", "threads"], "--set: expected NAME=VALUE"),
    (["--case", "models/slosh2d.toml", "--run", "0"], "--run/--step: need run > start time"),
    (["--case", "models/slosh2d.toml", "--config", "/no/such/zenoh.json5"], "zenoh.config:"),
])
def test_serve_refuses_bad_options_with_one_line(sphfmu_bin, args, needle):
    # sphfmu serve hands over to sphfmu-serve (built with the FMU crate, which has zenoh)
    serve = pathlib.Path(sphfmu_bin).with_name("sphfmu-serve")
    if not serve.exists():
        subprocess.run(["cargo", "build", "--release", "--workspace"], cwd=ROOT, check=True)
    r = run([sphfmu_bin, "serve", *args], cwd=ROOT, timeout=60)
    assert r.returncode != 0
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], r.stderr


def test_serve_on_a_busy_port_is_a_one_line_error(sphfmu_bin):
    import socket
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        r = run([sphfmu_bin, "serve", "--case", "models/slosh2d.toml", "--listen",
                 f"tcp/127.0.0.1:{port}"], cwd=ROOT, timeout=60)
    assert r.returncode == 1
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("sphfmu serve: zenoh.listen / zenoh.connect: cannot open a zenoh session")
    assert "Address already in use" in last
