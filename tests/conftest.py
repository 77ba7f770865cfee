"""Fixtures shared by the whole test suite."""
import pytest


@pytest.fixture(scope="session")
def sim_cache(tmp_path_factory):
    """A simulation cache shared by the tests of one session (simulate each run once)."""
    return tmp_path_factory.mktemp("sim-cache")
