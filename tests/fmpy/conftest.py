"""Shared fixtures: the release binary built by `make test` before pytest runs."""
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def sphfmu_bin():
    exe = ROOT / "target" / "release" / "sphfmu"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "--features", "mpi", "--bin", "sphfmu"], cwd=ROOT, check=True)
    return str(exe)


@pytest.fixture(scope="session")
def models():
    return ROOT / "models"


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "NO_COLOR": "1"}, **kw)


def run_session(script, name, timeout=600, **args):
    """Run session `name` of `script` (a sessions file next to this one) in a fresh Python
    process, so a crash in the FMU fails one test and pytest survives; its JSON result."""
    import json
    import sys
    here = pathlib.Path(__file__).resolve().parent
    p = subprocess.run([sys.executable, str(here / script), name, json.dumps(args)],
                       capture_output=True, text=True, cwd=here, timeout=timeout)
    assert p.returncode == 0, f"session {name} died (exit {p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}"
    return json.loads(p.stdout.strip().splitlines()[-1])


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "verify: a long co-simulation run by `make verify` (SPHFMU_VERIFY=1), not `make test`")


def pytest_collection_modifyitems(config, items):
    if os.environ.get("SPHFMU_VERIFY") == "1":
        return
    skip = pytest.mark.skip(reason="make verify runs it (SPHFMU_VERIFY=1)")
    for item in items:
        if "verify" in item.keywords:
            item.add_marker(skip)
