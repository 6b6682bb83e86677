"""tools/bench_goals.py, the verdicts of `make bench`: figures and ratios computed from the
measurement files as written, pass and short decided against each target, and the box cases
it builds for the cost comparison accepted by `sphfmu check`."""
import json
import subprocess
import sys

from conftest import ROOT, run

sys.path.insert(0, str(ROOT / "tools"))
import bench_goals  # noqa: E402


def row(d, n, rate, loop):
    return {"dimension": d, "particles": n, "particle_updates_per_second": rate,
            "force_loop_pairs_per_second_per_thread": loop}


def test_verdicts_from_table_and_peer_files(tmp_path):
    # 2D linear within 10 %, 3D off by 40 % at one size; one force loop below 1e8
    table = [row(2, 10000, 1.0e6, 1.2e8), row(2, 100000, 1.1e6, 1.3e8), row(2, 1000000, 0.95e6, 1.1e8),
             row(3, 10000, 3.0e5, 0.9e8), row(3, 100000, 5.0e5, 1.0e8), row(3, 1000000, 5.1e5, 1.0e8)]
    peer = [{"code": "sphfmu", "scheme": "standard", "threads": 2, "updates_per_s": 2.1e6},
            {"code": "sphfmu", "scheme": "psph", "threads": 2, "updates_per_s": 5.0e5},
            {"code": "PySPH 1.0b2", "scheme": "psph", "threads": 2, "updates_per_s": 1.0e5}]
    (tmp_path / "t.json").write_text(json.dumps(table))
    (tmp_path / "p.json").write_text(json.dumps(peer))
    out = tmp_path / "goals.md"
    r = run([sys.executable, str(ROOT / "tools" / "bench_goals.py"), "--skip-runs", "--out", str(out),
             "--table", str(tmp_path / "t.json"), "--peer", str(tmp_path / "p.json")])
    assert r.returncode == 0, r.stderr
    goals = {g["goal"]: g for g in json.loads((tmp_path / "goals.json").read_text())["goals"]}
    assert goals["force loop pairs/s per core"]["verdict"] == "short"  # 0.9e8 in 3D
    assert goals["cost linear in N, 2D"]["verdict"] == "pass"
    assert goals["cost linear in N, 3D"]["verdict"] == "short"
    std = goals["Noh 2D: our standard SPH / PySPH PSPH"]
    assert std["verdict"] == "pass" and std["figure"].startswith("21.0x")
    same = goals["Noh 2D: our PSPH / PySPH PSPH"]
    assert same["verdict"] == "short" and same["figure"].startswith("5.0x")
    # no CRKSPH row in this peer file: said so, not guessed
    assert goals["Noh 2D: our CRKSPH / PySPH CRKSPH"]["verdict"] == "unmeasured"
    assert "| **short** |" in out.read_text()


def test_cost_cases_are_valid_cases(sphfmu_bin, tmp_path):
    presets = bench_goals.preset_defaults()
    assert presets["crksph"] == ("septic-spline", "2", "crk-rk2", "0.25")
    for scheme in ("crksph", "rosswog-f1"):
        kernel, eta, integrator, cfl = presets[scheme]
        for name in ("standard", scheme):
            case = bench_goals.box_case(str(tmp_path / f"{scheme}-{name}.toml"), name, kernel, eta,
                                        integrator, cfl)
            text = open(case).read()
            assert f'name = "{name}"' in text and f'name = "{kernel}"' in text
            assert f'integrator = "{integrator}"' in text
            r = run([sphfmu_bin, "check", case])
            assert r.returncode == 0, r.stdout + r.stderr
