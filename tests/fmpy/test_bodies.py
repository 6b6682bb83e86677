"""A multibody master driving a 3D body through the FMU (issue 22): the box of
models/box3d.toml rolled and pitched together, its orientation as a quaternion or as Modelica's
R.T, loads in world and body axes, and orientations that are not rotations. Each session runs
in its own process (body_sessions.py)."""
import subprocess

import numpy as np
import pytest

from conftest import run_session
from test_fmu import ROOT

BOX = ROOT / "target" / "fmu" / "box3d" / "sphfmu.fmu"
BOX_MATRIX = ROOT / "target" / "fmu" / "box3d-matrix" / "sphfmu.fmu"


@pytest.fixture(scope="module", autouse=True)
def packaged():
    if not BOX.exists() or not BOX_MATRIX.exists():
        subprocess.run(["make", "fmu"], cwd=ROOT, check=True)


def session(name, **args):
    return run_session("body_sessions.py", name, **args)


def test_a_rolled_and_pitched_box_carries_the_hydrostatic_loads_of_level_water():
    # roll 0.12 rad and pitch 0.08 rad together over 0.6 s, hold to 1.5 s, average the loads
    # over the last 0.55 s (about one period of the first sloshing mode, 0.55 s); at FMU
    # resolution 0.8 (1.25 cm, 37 s on 2 cores; at 1 cm, 112 s: torques within 0.4 % and 1.2 %)
    r = session("tilted_box", fmu_path=str(BOX), roll=0.12, pitch=0.08, ramp=0.6, t_end=1.5,
                window=0.55, dt=0.01, resolution=0.8)
    assert r["finite"]
    weight = -r["expected_force"][2]
    force, torque = np.array(r["force"]), np.array(r["torque"])
    expected, frozen = np.array(r["expected_torque"]), np.array(r["frozen_torque"])
    # measured: vertical force within 6e-5 of the weight, horizontal 3e-4 of it
    assert abs(force[2] + weight) < 1e-3 * weight, r
    assert np.abs(force[:2]).max() < 2e-3 * weight, r
    # measured: roll and pitch torques within 1.6 % and 1.1 % of the level water's; water that
    # kept its place in the box (no level surface) would give 3.4 times as much
    assert np.abs(torque - expected).max() < 0.03 * np.abs(expected).max(), r
    assert np.abs(frozen - expected).max() > 10 * np.abs(torque - expected).max(), r
    # body-axes loads are the world loads turned by the box's orientation (measured 1.1e-16)
    assert r["body_frame_error"] < 1e-14, r


def test_a_quaternion_and_a_rotation_matrix_give_the_same_loads():
    r = session("quaternion_and_matrix", quaternion_fmu=str(BOX), matrix_fmu=str(BOX_MATRIX))
    # 120° about the diagonal is exact in both forms: the same bits
    quaternion, matrix = r["diagonal"]
    assert quaternion == matrix
    # a generic turn: the master's matrix and quaternion differ in the last bits only
    a, b = (np.array(x) for x in r["generic"])
    assert np.abs(a - b).max() < 1e-11 * np.abs(a).max(), (a, b)
    assert np.abs(a).max() > 1.0


def test_orientations_that_are_not_rotations_are_errors_that_change_nothing():
    r = session("bad_orientations", quaternion_fmu=str(BOX), matrix_fmu=str(BOX_MATRIX))
    # within 1e-6 of unit length: taken (and renormalised inside)
    assert r["near_unit_taken"][0] == pytest.approx(1.0, abs=1e-6)
    for k in ("nan", "zero", "long", "skew", "mirror", "fmi2_step"):
        assert r[k] == 3, (k, r)  # fmi3Error / fmi2Error
    assert r["kept"] == [1.0, 0.0, 0.0, 0.0]
    assert r["matrix_kept"] == [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    assert r["time_after"] == pytest.approx(0.01)
    assert r["fmi2_unchanged"] and r["fmi2_steps_on"]
    log = "\n".join(r["log"])
    for text in ("box.orientation: must be finite", "got length 0 ", "got length 1.01",
                 "box.T: must be orthonormal", "a reflection", "fmi2DoStep: box.orientation"):
        assert text in log, (text, log)
