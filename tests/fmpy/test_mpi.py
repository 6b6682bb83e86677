"""`mpirun -n R sphfmu run CASE` as a user starts it (issue 23): the same case on 1, 2 and 3
ranks (oversubscribed on a 2-core machine) writes the same particles, to the last printed
digit, for standard SPH, CRKSPH and Rosswog F1; the VTU snapshot is one .pvtu with a piece
per rank, which ParaView and meshio read; a case the decomposition does not handle yet is
refused with a reason."""
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


def test_case_with_walls_is_refused_on_several_ranks(sphfmu_bin, models, tmp_path):
    r = mpirun(2, [sphfmu_bin, "run", str(models / "closed-tank2d.toml"), "--out", str(tmp_path), "--quiet"])
    assert r.returncode != 0
    assert "not supported on several ranks yet" in r.stderr, r.stderr[-2000:]
