"""A trajectory generated block by block is the one-block trajectory to the last bit.

:func:`fuzzynav.sim.trajectory.generate` makes a run longer than ``BLOCK_SAMPLES`` in
blocks, carrying the running integrals (height, every latitude sweep, longitude) across;
here the block is made small so every shipped scenario family is cut into many blocks,
with boundaries on and off the segment boundaries, and compared array by array.
"""
import dataclasses

import numpy as np
import pytest

from fuzzynav.sim import trajectory
from fuzzynav.sim.scenario import load_scenario

_ARRAYS = ("time_s", "lla", "vel_n", "att", "q_bn", "dtheta_b", "dv_b", "omega_nb_b")


def _generate(scn):
    return trajectory.generate(scn.start_lla_rad, scn.segments, scn.imu.rate_hz,
                               scn.initial_speed_mps, np.deg2rad(scn.initial_heading_deg),
                               sea=scn.sea)


@pytest.mark.parametrize("name", ["paper000", "paper001", "paper003", "paper004",
                                  "paper000-route-spiral"])
def test_blocks_give_the_one_block_trajectory(name, monkeypatch):
    scn = load_scenario(name)
    whole = _generate(scn)
    assert whole.n_samples <= trajectory.BLOCK_SAMPLES  # today's one-block path
    # 1000 samples: blocks end on whole seconds (often on a segment boundary); 997: never
    for block in (1000, 997):
        monkeypatch.setattr(trajectory, "BLOCK_SAMPLES", block)
        parts = _generate(scn)
        assert parts.n_samples > 10 * block
        for f in _ARRAYS:
            np.testing.assert_array_equal(getattr(parts, f), getattr(whole, f), err_msg=f)


def test_a_block_of_one_sample_and_a_last_short_block(monkeypatch):
    scn = load_scenario("paper003")
    cruise, turn = scn.segments[:2]  # 20 s of them: a cruise, then a turn on the sea
    short = dataclasses.replace(scn, segments=(dataclasses.replace(cruise, duration_s=10.0),
                                               dataclasses.replace(turn, duration_s=10.0,
                                                                   turn_deg=30.0)))
    whole = _generate(short)
    for block in (1, whole.n_samples - 1):
        monkeypatch.setattr(trajectory, "BLOCK_SAMPLES", block)
        parts = _generate(short)
        for f in _ARRAYS:
            np.testing.assert_array_equal(getattr(parts, f), getattr(whole, f), err_msg=f)
