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
        subprocess.run(["cargo", "build", "--release", "--bin", "sphfmu"], cwd=ROOT, check=True)
    return str(exe)


@pytest.fixture(scope="session")
def models():
    return ROOT / "models"


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "NO_COLOR": "1"}, **kw)
