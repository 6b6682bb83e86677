"""A 3D rectangular tank pitched near its first sloshing mode through the FMU (issue 22,
`make verify`): models/pitch3d.toml turned about y by a master, 0.02 rad at 0.95 w1 for two
periods, then held level. The free sloshing that follows is compared with linear theory, and
the peak pressure at the wall marker is reported."""
import math
import subprocess

import numpy as np
import pytest

from conftest import run_session
from signals import modes
from test_fmu import ROOT

FMU = ROOT / "target" / "fmu" / "pitch3d" / "sphfmu.fmu"


@pytest.fixture(scope="module", autouse=True)
def packaged():
    if not FMU.exists():
        subprocess.run(["make", "fmu"], cwd=ROOT, check=True)


@pytest.mark.verify
def test_a_pitched_tank_sloshes_at_the_linear_first_mode():
    g, length, depth = 9.81, 0.4, 0.12
    k = math.pi / length
    w1 = math.sqrt(g * k * math.tanh(k * depth))
    r = run_session("body_sessions.py", "pitched_tank", fmu_path=str(FMU), amplitude=0.02,
                    omega=0.95 * w1, cycles=2, free_time=2.0, dt=0.02, timeout=3600)
    rows = np.array(r["rows"])
    t, p, fx = rows[:, 0], rows[:, 1], rows[:, 2]
    free = t > r["forced"] + 0.1
    (w, zeta), = modes(fx[free] - fx[free].mean(), 0.02, order=2)
    hydrostatic = 1000.0 * g * 0.06
    peak = float(p[~free].max())
    print(f"\nfree sloshing: {w:.4f} rad/s (T = {2 * math.pi / w:.4f} s) against linear theory "
          f"{w1:.4f} rad/s (T1 = {2 * math.pi / w1:.4f} s), damping ratio {zeta:.4f}; "
          f"peak wall pressure at the marker {peak:.1f} Pa (hydrostatic {hydrostatic:.1f} Pa)")
    assert np.all(np.isfinite(rows))
    # measured: 7.5523 rad/s against 7.5322 (+0.27 %; 9 particles deep); the 2 s of free
    # sloshing (2.4 periods) do not resolve its damping (the fit gives -0.005); peak wall
    # pressure 741.2 Pa at the marker, hydrostatic 588.6 Pa (6 min on 2 cores)
    assert abs(w / w1 - 1.0) < 0.03, (w, w1)
    assert hydrostatic < peak < 3.0 * hydrostatic
