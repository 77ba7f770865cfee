"""Ship motion (sea state), the electromagnetic log and the ship's constraint pseudo-measurements."""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude, earth, strapdown
from fuzzynav.sim import sensors
from fuzzynav.sim.sea import SeaState
from fuzzynav.sim.trajectory import Segment, generate

START = np.array([np.deg2rad(28.68), np.deg2rad(115.89), 0.0])
SEA = SeaState(roll_deg=5.0, roll_period_s=10.0, pitch_deg=2.0, pitch_period_s=7.0,
               yaw_deg=1.0, yaw_period_s=15.0, heave_m=0.5, heave_period_s=8.0,
               current_mps=(0.3, -0.4))
SEGS = [Segment("cruise", 60), Segment("turn", 60, turn_deg=60),
        Segment("accelerate", 30, speed_change_mps=3)]


@pytest.fixture(scope="module")
def ship():
    return generate(START, SEGS, 50.0, 8.0, 0.5, sea=SEA)


def test_sea_state_replay_stays_on_truth(ship):
    """The increments of a rolling, heaving ship integrate back to its truth (exactness)."""
    out = strapdown.integrate(ship.lla[0], ship.vel_n[0], ship.q_bn[0], ship.dtheta_b,
                              ship.dv_b, 0.02, stride=50)
    idx = np.arange(0, ship.n_samples + 1, 50)
    err = np.array([earth.lla_to_enu(*a, *b) for a, b in zip(out["lla"], ship.lla[idx])])
    assert np.abs(err).max() < 0.05
    phi = attitude.attitude_error(attitude.quat_to_dcm(out["q_bn"]),
                                  attitude.quat_to_dcm(ship.q_bn[idx]))
    assert np.rad2deg(np.abs(phi)).max() < 1e-3


def test_sea_state_amplitudes_and_heave(ship):
    t = ship.time_s
    # roll and pitch oscillate with the requested amplitudes (track pitch and roll are 0)
    assert np.rad2deg(np.abs(ship.att[:, 1]).max()) == pytest.approx(5.0, abs=0.05)
    assert np.rad2deg(np.abs(ship.att[:, 0]).max()) == pytest.approx(2.0, abs=0.05)
    # heave: height follows 0.5 sin(2 pi t / 8) (velocity integrated by quadrature)
    np.testing.assert_allclose(ship.lla[:, 2], 0.5 * np.sin(2 * np.pi * t / 8.0), atol=1e-3)
    # the ground velocity stays horizontal along the track, up to the heave rate
    np.testing.assert_allclose(ship.vel_n[:, 2], 0.5 * 2 * np.pi / 8 * np.cos(2 * np.pi * t / 8),
                               atol=1e-9)


def test_current_constant_ramped_and_varying():
    sea = SeaState(current_mps=(0.3, 0.4), current_var_mps=0.1, current_var_period_s=400.0,
                   current_changes=((100.0, 200.0, -0.6, 0.0),))
    c = sea.current_n(np.array([0.0, 100.0, 150.0, 200.0, 300.0]))
    u = np.array([0.6, 0.8])
    var = 0.1 * np.sin(2 * np.pi * np.array([0.0, 100.0, 150.0, 200.0, 300.0]) / 400.0)
    base = np.array([0.3, 0.4]) + var[:, None] * u
    ramp = np.array([0.0, 0.0, 0.5, 1.0, 1.0])  # cycloidal ramp: half way at the middle
    np.testing.assert_allclose(c[:, :2], base + ramp[:, None] * [-0.6, 0.0], atol=1e-12)
    assert np.all(c[:, 2] == 0.0)


def test_log_reads_forward_speed_through_water(ship):
    """No noise: the reading is (1 + k) times the keel component of (v - current) plus b."""
    spec = sensors.spec_class("log").from_dict({"noise_mps": 0.0, "claimed_sigma_mps": 0.5,
                                                "bias_mps": 0.5, "scale": 0.01}, "sensors.log")
    d = spec.simulate(ship, np.random.default_rng(0))
    idx = np.round(d.time_s * 50.0).astype(int)
    heading = ship.att[idx, 2]
    # independent: the keel direction from the heading and pitch (roll does not move it)
    pitch = ship.att[idx, 0]
    keel = np.stack([np.sin(heading) * np.cos(pitch), np.cos(heading) * np.cos(pitch),
                     np.sin(pitch)], -1)
    water = ship.vel_n[idx] - np.array([0.3, -0.4, 0.0])
    expect = 1.01 * np.sum(keel * water, 1) + 0.5
    np.testing.assert_allclose(d.z[:, 0], expect, atol=1e-9)
    np.testing.assert_allclose(d.meta["current_fwd_mps"], keel @ [0.3, -0.4, 0.0], atol=1e-12)


def test_log_noise_has_the_stated_sigma(ship):
    spec = sensors.spec_class("log").from_dict({"bias_mps": 0.0}, "sensors.log")
    d = spec.simulate(ship, np.random.default_rng(1))
    clean = spec.__class__(noise_mps=0.0, bias_mps=0.0, claimed_sigma_mps=0.5).simulate(
        ship, np.random.default_rng(1))
    err = d.z[:, 0] - clean.z[:, 0]
    assert err.std() == pytest.approx(0.5, rel=0.05)  # 7 500 samples: ~1 % standard error
    assert abs(err.mean()) < 0.03


def test_nhc_carries_lateral_current_and_leeway(ship):
    spec = sensors.spec_class("nhc").from_dict({"leeway_deg": 2.0, "rate_hz": 5.0}, "sensors.nhc")
    d = spec.simulate(ship, np.random.default_rng(0))
    idx = np.round(d.time_s * 50.0).astype(int)
    h = ship.att[idx, 2]
    C_bn = attitude.quat_to_dcm(ship.q_bn[idx])
    lateral_current = C_bn[:, 0, 0] * 0.3 + C_bn[:, 1, 0] * -0.4
    water_fwd = np.einsum("kj,kj->k", C_bn[:, :, 1], ship.vel_n[idx] - [0.3, -0.4, 0.0])
    np.testing.assert_allclose(d.z[:, 0], -(lateral_current
                                            + water_fwd * np.tan(np.deg2rad(2.0))), atol=1e-9)
    assert np.all(d.z[:, 1] == 0.0) and np.all(d.sigma == 0.2)
    assert h.size == d.z.shape[0]


def test_bad_sea_and_log_tables_name_the_key():
    with pytest.raises(InputFileError, match="sea.roll_deg"):
        SeaState.from_dict({"roll_deg": -1.0})
    with pytest.raises(InputFileError, match="sea.current_changes"):
        SeaState.from_dict({"current_changes": [[10.0, 5.0, 0.1, 0.1]]})
    with pytest.raises(InputFileError, match="sensors.log.claimed_sigma_mps"):
        sensors.spec_class("log").from_dict({"noise_mps": 0.0}, "sensors.log")
    with pytest.raises(InputFileError, match="sensors.nhc.leeway"):
        sensors.spec_class("nhc").from_dict({"leeway": 1.0}, "sensors.nhc")
