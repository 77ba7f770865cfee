"""Fixtures of the tuning tests."""
import pytest


@pytest.fixture(scope="session")
def sim_cache(tmp_path_factory):
    """A simulation cache shared by the tuning tests of one session (each run simulated once)."""
    return tmp_path_factory.mktemp("tuning-sim-cache")
