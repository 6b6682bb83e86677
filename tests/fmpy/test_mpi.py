"""`mpirun -n R sphfmu run CASE` as a user starts it (issue 23): the same case on 1, 2 and 3
ranks (oversubscribed on a 2-core machine) writes the same particles, to the last printed
digit, for standard SPH, CRKSPH and Rosswog F1; the VTU snapshot is one .pvtu with a piece
per rank, which ParaView and meshio read; a body's walls and ports give the same particles
on 1 and 2 ranks, and the same loads and flows to round-off."""
import os
import re
import shutil

import meshio
import numpy as np
import pytest

from conftest import run

MPIRUN = shutil.which("mpirun")
pytestmark = pytest.mark.skipif(MPIRUN is None, reason="Open MPI's mpirun is not installed (make openmpi)")


def mpirun(n, args, timeout=600):
    # root in containers and CI: Open MPI refuses root unless told twice
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1", "NO_COLOR": "1"}
    import subprocess
    return subprocess.run([MPIRUN, "--oversubscribe", "-n", str(n), *args],
                          capture_output=True, text=True, env=env, timeout=timeout)


@pytest.mark.parametrize("scheme", ["standard", "crksph", "rosswog-f1"])
def test_noh_is_the_same_on_1_2_3_ranks(sphfmu_bin, models, tmp_path, scheme):
    texts = {}
    for n in (1, 2, 3):
        out = tmp_path / f"r{n}"
        r = mpirun(n, [sphfmu_bin, "run", str(models / "noh2d.toml"), "--scheme", scheme,
                       "--set", "time.t_end=0.03", "--out", str(out), "--quiet"])
        assert r.returncode == 0, f"{n} ranks: {r.stdout[-1500:]}\n{r.stderr[-2000:]}"
        # rank 0 alone prints the summary, once
        assert r.stdout.count("particle-updates/s") == 1, r.stdout
        if n > 1:
            assert re.search(rf"^{n} ranks: rank 0 sent [0-9.e+]+ bytes", r.stdout, re.M), r.stdout
        texts[n] = (out / "snapshot_00001.csv").read_text()
    for n in (2, 3):
        # the first differing row, not pytest's diff of two megabyte strings (which takes
        # many minutes)
        first = next((i for i, (a, b) in enumerate(zip(texts[1].splitlines(), texts[n].splitlines()))
                      if a != b), None)
        same = texts[1] == texts[n]
        assert same, f"{scheme}: {n} ranks differ from 1 at snapshot row {first}"


def test_pvtu_joins_one_piece_per_rank(sphfmu_bin, models, tmp_path):
    r = mpirun(3, [sphfmu_bin, "run", str(models / "noh2d.toml"), "--set", "time.t_end=0.01",
                   "--out", str(tmp_path), "--quiet"])
    assert r.returncode == 0, r.stderr[-2000:]
    pvtu = (tmp_path / "snapshot_00001.pvtu").read_text()
    pieces = re.findall(r'<Piece Source="([^"]+)"/>', pvtu)
    assert pieces == [f"snapshot_00001_{k}.vtu" for k in range(3)]
    ids = np.concatenate([meshio.read(tmp_path / p).point_data["id"] for p in pieces])
    # every particle in exactly one piece
    assert sorted(ids.tolist()) == list(range(len(ids))) and len(ids) == 100 * 100
    assert 'snapshot_00001.pvtu' in (tmp_path / "snapshots.pvd").read_text()


def _columns(path):
    """A CSV with a header row as a float array (one row per line)."""
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("model,sets,loads", [
    # walls of a body: the hydrostatic closed tank, and its load history
    ("closed-tank2d.toml", ["time.t_end=0.05"], "bodies.csv"),
    # a body with two ports, driven hard enough that particles enter and leave within the run
    # (the first leaves through the outlet at t = 0.59)
    ("channel-ports2d.toml", ["time.t_end=1.0", "region.0.spacing=0.1",
                              'port.0.pressure={ type = "constant", value = 3.0 }'], "ports.csv"),
])
def test_walls_and_ports_are_the_same_on_1_and_2_ranks(sphfmu_bin, models, tmp_path, model, sets, loads):
    outs = {}
    for n in (1, 2):
        out = tmp_path / f"r{n}"
        args = [sphfmu_bin, "run", str(models / model), "--out", str(out), "--quiet",
                "--set", "output.snapshot_every=0.0", "--set", 'output.formats=["csv"]']
        for s in sets:
            args += ["--set", s]
        r = mpirun(n, args)
        assert r.returncode == 0, f"{n} ranks: {r.stdout[-1500:]}\n{r.stderr[-2000:]}"
        outs[n] = out
    last = sorted(p.name for p in outs[1].glob("snapshot_*.csv"))[-1]
    same = (outs[1] / last).read_bytes() == (outs[2] / last).read_bytes()
    assert same, f"{model}: the particles of {last} differ on 2 ranks"
    # loads and flows are sums of per-rank sums: equal to round-off
    a, b = _columns(outs[1] / loads), _columns(outs[2] / loads)
    assert a.shape == b.shape and np.abs(a).max() > 0
    assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(a).max()), f"{loads}: {np.abs(a - b).max()}"
    if loads == "ports.csv":
        # columns per port: mean pressure, volume flow, mass in, mass out
        assert a[-1, 3] > 0 and a[-1, 8] > 0, "no particle crossed a port"
