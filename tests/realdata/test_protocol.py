"""The validation protocol's parts on hand-made data (no recording needed)."""
import math

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.result import FilterResult
from fuzzynav.metrics import NavErrors
from fuzzynav.nav import attitude, earth
from fuzzynav.realdata import protocol
from fuzzynav.realdata.protocol import ProtocolSettings
from fuzzynav.realdata.score import antenna_track, outage_drifts, score
from fuzzynav.sim.sensors import SensorData

LAT0, LON0, H0 = np.radians(40.0), np.radians(-105.0), 1600.0


def _fixes(t, vel_e):
    m = t.size
    z = np.column_stack([np.full(m, LAT0), np.full(m, LON0), np.full(m, H0),
                         vel_e, np.zeros(m), np.zeros(m)])
    sigma = np.tile([0.01, 0.01, 0.02, 0.03, 0.03, 0.05], (m, 1))
    return SensorData("gnss", t, z, sigma, {"lever_arm_b": np.zeros(3), "q": np.ones(m)})


# -- outage windows -----------------------------------------------------------------------
def test_default_windows_start_one_period_after_the_filter():
    w = protocol.windows_after(20.3, 549.4, ProtocolSettings())
    # 20.3 + 180 = 200.3, + 180 = 380.3; 560.3 is after the end
    np.testing.assert_allclose(w, [[200.3, 260.3], [380.3, 440.3]])


def test_windows_with_an_earlier_first_outage_and_none():
    s = ProtocolSettings(first_outage_s=40.0, outage_period_s=100.0, outage_duration_s=30.0)
    np.testing.assert_allclose(protocol.windows_after(10.0, 300.0, s),
                               [[50.0, 80.0], [150.0, 180.0], [250.0, 280.0]])
    assert protocol.windows_after(10.0, 300.0, ProtocolSettings(outage_duration_s=0.0)).shape \
        == (0, 2)


def test_outages_remove_exactly_the_epochs_inside():
    t = np.arange(0.0, 100.0, 0.25)
    fed = protocol.with_outages(_fixes(t, np.zeros(t.size)), np.array([[10.0, 20.0]]))
    gone = (t >= 10.0) & (t < 20.0)
    np.testing.assert_array_equal(fed.time_s, t[~gone])
    assert fed.meta["q"].size == fed.time_s.size


@pytest.mark.parametrize("kw", [dict(velocity="late"), dict(noise_pos_m=-1.0),
                                dict(outage_period_s=30.0), dict(first_outage_s=-5.0)])
def test_bad_settings_are_refused(kw):
    with pytest.raises(FuzzynavError):
        ProtocolSettings(**kw)


@pytest.mark.parametrize("field, value", [
    ("noise_pos_m", math.inf), ("noise_pos_m", math.nan), ("noise_pos_m", 1e300),
    ("noise_vel_mps", math.inf), ("velocity_lag_s", math.nan), ("velocity_lag_s", -math.inf),
    ("t_start_s", math.inf), ("nhc_sigma_mps", 1e9), ("outage_period_s", math.inf)])
def test_a_number_that_is_not_finite_or_beyond_its_limit_is_refused_by_name(field, value):
    # infinite noise ran and diverged (exit 3), an infinite lag failed later with a message
    # about the GNSS fixes
    with pytest.raises(FuzzynavError, match=rf"{field} must lie in \["):
        ProtocolSettings(**{field: value})


def test_the_limits_admit_the_defaults_and_the_documented_settings():
    ProtocolSettings()
    ProtocolSettings(noise_pos_m=0.0, velocity="inflate", velocity_lag_s=-0.2,
                     first_outage_s=0.0, outage_duration_s=0.0, nhc_sigma_mps=0.3)


# -- the fed copy -------------------------------------------------------------------------
def test_shift_reads_the_velocity_later():
    t = np.arange(0.0, 10.0, 0.25)
    fixes = _fixes(t, 2.0 * t)                   # a ramp: v(t + lag) = v(t) + 2 lag
    s = ProtocolSettings(noise_pos_m=0.0, velocity="shift", velocity_lag_s=0.14)
    fed = protocol.degraded_fixes(fixes, s, np.random.default_rng(0))
    inner = t < t[-1] - 0.14                     # the last epoch holds the end value
    np.testing.assert_allclose(fed.z[inner, 3], 2.0 * (t[inner] + 0.14), atol=1e-12)
    np.testing.assert_allclose(fed.z[:, :3], fixes.z[:, :3], atol=0)


def test_inflate_adds_in_quadrature_and_noise_inflates_positions():
    t = np.arange(0.0, 10.0, 0.25)
    fixes = _fixes(t, np.ones(t.size))
    s = ProtocolSettings(noise_pos_m=2.0, velocity="inflate", velocity_inflate_mps=0.16)
    fed = protocol.degraded_fixes(fixes, s, np.random.default_rng(0))
    np.testing.assert_allclose(fed.sigma[:, 3], np.hypot(0.03, 0.16))
    np.testing.assert_allclose(fed.sigma[:, 0], np.hypot(0.01, 2.0))
    np.testing.assert_array_equal(fed.z[:, 3], 1.0)      # values untouched
    north_m = (fed.z[:, 0] - LAT0) * earth.radii(LAT0)[0]
    assert north_m.std() > 1.2 and north_m.std() < 2.8                    # 2 m added (40 epochs: ±0.22)


# -- scoring ------------------------------------------------------------------------------
def _errors_east(t, e):
    z = np.zeros((t.size, 3))
    return NavErrors(t, np.column_stack([e, z[:, 0], z[:, 0]]), z, np.full_like(z, np.nan))


def test_drift_is_read_before_the_first_fix_after_the_outage():
    t_ref = np.arange(0.0, 100.0, 0.25)          # reference epochs (4 Hz)
    t_res = np.arange(0.0, 100.05, 0.1)          # solution samples (10 Hz)
    a, b = 20.0, 80.0
    # the solution's error grows as (t - a)^2 in the outage and is reset at b; the
    # reference-epoch errors are its linear interpolation (as errors_vs_reference makes)
    e_res = np.where((t_res >= a) & (t_res < b), (t_res - a) ** 2, 0.0)
    err = _errors_east(t_ref, np.interp(t_ref, t_res, e_res))
    d, = outage_drifts(err, t_res, [[a, b]])
    # last solution sample before b is 79.9; the last reference epoch not after it is
    # 79.75, between samples 79.7 and 79.8: (59.7^2 + 59.8^2) / 2
    assert d.complete and d.t_read_s == pytest.approx(79.75)
    assert d.drift_h_m == pytest.approx((59.7**2 + 59.8**2) / 2, rel=1e-12)
    assert d.max_h_m == pytest.approx(d.drift_h_m)


def test_outage_past_the_end_is_not_scored():
    t = np.arange(0.0, 50.0, 0.25)
    err = _errors_east(t, np.ones(t.size))
    full, cut = outage_drifts(err, np.arange(0.0, 50.0, 0.1), [[10.0, 20.0], [40.0, 60.0]])
    assert full.complete and full.drift_h_m == pytest.approx(1.0)
    assert not cut.complete and np.isnan(cut.drift_h_m)


def test_score_rms_outside_and_drift_statistics():
    t = np.arange(0.0, 100.0, 0.25)
    e = np.where((t >= 20) & (t < 40), 30.0, np.where((t >= 60) & (t < 80), 40.0, 3.0))
    m = score(_errors_east(t, e), np.arange(0.0, 100.05, 0.1), [[20, 40], [60, 80]])
    assert m["rms_pos_h_aided_m"] == pytest.approx(3.0)
    assert (m["drift_h_m_1"], m["drift_h_m_2"]) == pytest.approx((30.0, 40.0))
    assert m["drift_h_rms_m"] == pytest.approx(np.sqrt((30**2 + 40**2) / 2))
    assert m["drift_h_max_m"] == pytest.approx(40.0) and m["n_outages"] == 2


def test_antenna_is_moved_by_the_rotated_lever_arm():
    # heading 90 deg (east): the body's forward axis (y) points east
    q = attitude.euler_to_quat(np.array([0.0, 0.0, np.pi / 2]))
    res = FilterResult(time_s=np.zeros(1), lla=np.array([[LAT0, LON0, H0]]),
                       vel_n=np.zeros((1, 3)), q_bn=q[None], sensor_states=np.zeros((1, 6)),
                       sigma=np.zeros((1, 15)), state_labels=())
    moved = antenna_track(res, [0.0, 2.0, 0.5])
    enu = earth.delta_lla_to_enu(*(moved.lla[0] - res.lla[0]), LAT0, H0)
    np.testing.assert_allclose(enu, [2.0, 0.0, 0.5], atol=1e-6)
