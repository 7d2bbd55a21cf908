"""Shared fixtures: the repository, the built tool and the records."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
# The real records, beside the repository (never copied into it).
DATA = REPO / ".." / "shared" / "data" / "imu"
ADIS = DATA / "adis16405_imu1_part1.csv"


def _tool_command():
    """The tool: $IMU_AR_TOOL, or `cargo run -q -p imu-ar-cli --` in the repository."""
    given = os.environ.get("IMU_AR_TOOL")
    if given:
        return [given]
    if shutil.which("cargo") is None:
        pytest.skip("no cargo to run the imu-ar tool with (set IMU_AR_TOOL)")
    return ["cargo", "run", "-q", "-p", "imu-ar-cli", "--"]


@pytest.fixture(scope="session")
def tool():
    """Runs `imu-ar ARGS` and returns its stdout (an error fails the test)."""
    base = _tool_command()

    def run(*args):
        r = subprocess.run([*base, *map(str, args)], cwd=REPO, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        return r.stdout

    def run_json(*args):
        return json.loads(run(*args, "--json"))

    run.json = run_json
    return run


@pytest.fixture(scope="session")
def adis():
    if not ADIS.is_file():
        pytest.skip(f"{ADIS} is not there")
    return ADIS


@pytest.fixture(scope="session")
def white_walk():
    """Generated white noise plus a random walk, seeded."""
    rng = np.random.default_rng(38)
    n = 200_000
    return rng.normal(0.0, 0.05, n) + np.cumsum(rng.normal(0.0, 2e-4, n))


@pytest.fixture
def small_csv(tmp_path, white_walk):
    """A small generated CSV record at 100 Hz with a time column."""
    x = white_walk[:50_000]
    path = tmp_path / "small.csv"
    t = np.arange(len(x)) / 100.0
    with open(path, "w") as f:
        f.write("t_s,gx\n")
        for ti, xi in zip(t, x):
            f.write(f"{ti:.2f},{float(xi)!r}\n")
    return path, x
