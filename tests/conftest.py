"""Fixtures shared by the whole test suite.

Real recordings are looked for in ``$FUZZYNAV_DATA`` (default ``../shared/datasets``
relative to the repository root); a fresh clone has none, and the tests that need one skip
with the missing path in the message.
"""
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# The cold-start compile helper (fuzzynav.filters.precompile) shares a first run's
# compilation with a second process; under pytest-xdist every worker on a cold cache would
# start its own, so the suite runs without it (its protocol has its own tests).
os.environ.setdefault("FUZZYNAV_PRECOMPILE", "0")


@pytest.fixture(scope="session")
def sim_cache(tmp_path_factory):
    """A simulation cache shared by the tests of one session (simulate each run once)."""
    return tmp_path_factory.mktemp("sim-cache")


def datasets_dir() -> Path:
    """Where the real recordings are looked for."""
    return Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets"))


@pytest.fixture(scope="session")
def rtklib_drive() -> Path:
    """The rtklib-drive recording directory (skips the test when absent)."""
    path = datasets_dir() / "rtklib-drive"
    if not (path / "imu_1934.csv").is_file():
        pytest.skip(f"real recording not found: {path} (set FUZZYNAV_DATA)")
    return path
