"""A tuned liquid damper coupled two ways (issue 22, `make verify`): the sloshing tank of
models/tld2d.toml on a structure of M = 2500 kg/m and a spring tuned to the first sloshing
mode, k = (M + m) w1^2, integrated by tools/strong_coupling.py (explicit: the water is a fifth
of the structure's mass, so no added-mass trouble). The structure swings in two coupled
modes; their frequencies are compared with the linear equivalent mechanical model (Housner;
Ibrahim 2005) and their damping ratios, which the water adds, are reported."""
import math
import subprocess
import sys

import numpy as np
import pytest

from test_fmu import ROOT

sys.path.insert(0, str(ROOT / "tools"))
import strong_coupling  # noqa: E402
from signals import modes  # noqa: E402

FMU = ROOT / "target" / "fmu" / "tld2d" / "sphfmu.fmu"
M, K = 2500.0, 84800.0


@pytest.fixture(scope="module", autouse=True)
def packaged():
    if not FMU.exists():
        subprocess.run(["make", "fmu"], cwd=ROOT, check=True)


def equivalent_mechanical_model(rho=1000.0, length=1.0, depth=0.5, g=9.81):
    """The two coupled angular frequencies of the structure (M + m0, spring K) carrying the
    first sloshing mode as a mass m1 on a spring k1 = m1 w1^2 (models/tld2d.toml)."""
    m = rho * length * depth
    r = math.pi * depth / length
    m1 = m * 8.0 * math.tanh(r) / (math.pi ** 3 * depth / length)
    w1 = math.sqrt(g * math.pi / length * math.tanh(r))
    k1 = m1 * w1 ** 2
    stiffness = np.array([[K + k1, -k1], [-k1, k1]])
    mass = np.diag([M + m - m1, m1])
    return np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real)), w1


@pytest.mark.verify
def test_a_tuned_liquid_damper_splits_the_structure_mode_in_two():
    rec = strong_coupling.run(str(FMU), "tank", M, 0.02, 20.0, mode="explicit",
                              stiffness=(K, 0.0, 0.0), gravity=(0.0, -9.81, 0.0),
                              displace=(0.01, 0.0, 0.0), free="x", threads=2)
    assert rec["diverged"] is None
    x = np.array(rec["x"])[:, 0]
    found = modes(x - x.mean(), 0.02)
    (w_low, z_low), (w_high, z_high) = found
    theory, w1 = equivalent_mechanical_model()
    print(f"\ncoupled modes: {w_low:.4f} and {w_high:.4f} rad/s (model {theory[0]:.4f}, "
          f"{theory[1]:.4f}; tank alone {w1:.4f}); damping ratios {z_low:.4f}, {z_high:.4f}")
    # measured: 4.718 and 6.271 rad/s against 4.698 and 6.269 (+0.4 %, +0.03 %)
    assert abs(w_low / theory[0] - 1.0) < 0.02 and abs(w_high / theory[1] - 1.0) < 0.02
    # the water damps both modes: measured 1.5 % and 1.2 % of critical
    assert 0.002 < z_low < 0.05 and 0.002 < z_high < 0.05
