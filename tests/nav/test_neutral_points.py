"""Neutral-point sky model, the fisheye line angle, the simulated camera and its filter model."""
import datetime as dt

import numpy as np
import pytest

from fuzzynav.filters.measurements import default_rows, get
from fuzzynav.nav import attitude, strapdown
from fuzzynav.nav.neutral_points import heading_from_beta, images, neutral_points_n
from fuzzynav.sim import sun
from fuzzynav.sim.sensors.neutral_point import Spec
from fuzzynav.sim.trajectory import Segment, generate
from tests.filters.test_measurements import _perturbed

START = np.array([np.deg2rad(28.68), np.deg2rad(115.89), 0.0])
UTC = dt.datetime(2015, 10, 14, 23, 15, tzinfo=dt.timezone.utc)  # sun ~12 deg high


def _sun(elev_deg, az_deg):
    e, a = np.deg2rad(elev_deg), np.deg2rad(az_deg)
    return np.array([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)])


@pytest.mark.parametrize("elev", [5.0, 20.0, 45.0, 80.0])
def test_points_lie_on_the_solar_meridian_at_delta(elev):
    """Closed form of the model: delta from the sun (antisun), in its vertical plane."""
    s, delta = _sun(elev, 130.0), np.deg2rad(20.0)
    pts = np.zeros((4, 3))
    neutral_points_n(s, delta, pts)
    for k, ref in enumerate([s, s, -s, -s]):
        assert np.arccos(np.clip(pts[k] @ ref, -1, 1)) == pytest.approx(delta, abs=1e-12)
        # coplanar with the zenith and the sun: on the solar meridian
        assert np.linalg.det(np.array([pts[k], s, [0, 0, 1.0]])) == pytest.approx(0, abs=1e-12)
    # Babinet above the sun, Brewster below it, Arago above the antisun
    assert pts[0, 2] > s[2] > pts[1, 2] and pts[2, 2] > -s[2] > pts[3, 2]


def test_heading_from_the_two_points_of_a_noise_free_level_image():
    s = _sun(15.0, 110.0)
    for heading in np.deg2rad([0.0, 37.0, 180.0, 300.0]):
        C = attitude.euler_to_dcm(np.array([0.0, 0.0, heading]))
        img = images(C, s, np.deg2rad(20.0))
        beta = np.arctan2(img[0, 1] - img[2, 1], img[0, 0] - img[2, 0])  # Arago -> Babinet
        got = heading_from_beta(beta, np.deg2rad(110.0))
        assert attitude.wrap_pi(got - heading) == pytest.approx(0.0, abs=1e-12)


def test_simulated_camera_gives_heading_on_a_level_ship():
    tr = generate(START, [Segment("cruise", 20), Segment("turn", 20, turn_deg=90)], 50.0, 5.0, 0.3)
    d = Spec(angle_noise_rad=0.0, claimed_sigma_rad=0.005).simulate(tr, np.random.default_rng(0),
                                                                    UTC)
    assert d.z.shape[0] > 300 and np.all(d.z[:, 4] == 0)  # low sun: Arago and Babinet
    idx = np.round(d.time_s * 50).astype(int)
    az = np.arctan2(d.z[:, 1], d.z[:, 2])
    err = attitude.wrap_pi(heading_from_beta(d.z[:, 0], az) - tr.att[idx, 2])
    assert np.abs(err).max() < 1e-9


def test_failures_high_sun_clouds_and_the_short_pair():
    tr = generate(START, [Segment("cruise", 30)], 50.0, 5.0, 0.3)
    noon = dt.datetime(2015, 6, 21, 4, 15, tzinfo=dt.timezone.utc)  # sun ~85 deg high
    assert Spec().simulate(tr, np.random.default_rng(0), noon).z.shape[0] == 0
    cloudy = Spec(clouds=((0.0, 10.0, 0.0), (10.0, 20.0, 5.0)))
    d = cloudy.simulate(tr, np.random.default_rng(0), UTC)
    assert d.time_s.min() >= 10.0
    assert d.meta["true_sigma"][d.time_s < 20, 0].mean() > 4 * d.meta["true_sigma"][
        d.time_s >= 20, 0].mean()
    morning = dt.datetime(2015, 10, 15, 2, 0, tzinfo=dt.timezone.utc)  # ~45 deg: no Arago
    d = Spec().simulate(tr, np.random.default_rng(0), morning)
    assert np.all(d.z[:, 4] == 1)
    # a 40-deg baseline instead of 140: beta noise grows by the ratio
    assert d.meta["true_sigma"][0, 0] == pytest.approx(0.005 * 140 / 40, rel=0.02)


def test_noise_has_the_paper_accuracy_on_the_arago_babinet_pair():
    tr = generate(START, [Segment("cruise", 200)], 50.0, 5.0, 0.3)
    d = Spec(rate_hz=50.0).simulate(tr, np.random.default_rng(3), UTC)
    clean = Spec(rate_hz=50.0, angle_noise_rad=0.0, claimed_sigma_rad=0.005).simulate(
        tr, np.random.default_rng(3), UTC)
    err = attitude.wrap_pi(d.z[:, 0] - clean.z[:, 0])
    assert err.std() == pytest.approx(0.005, rel=0.06)


def test_a_detector_faster_than_the_imu_averages_its_detections():
    """Paper 003's 100-Hz detector on the 50-Hz IMU: one output per IMU sample, the mean of
    two detections, so the noise and the claimed sigma are 0.005 / sqrt(2) (6 % tolerance:
    the standard error of a std from ~10 000 samples is 0.7 %, as in the test above)."""
    tr = generate(START, [Segment("cruise", 200)], 50.0, 5.0, 0.3)
    d = Spec(rate_hz=100.0).simulate(tr, np.random.default_rng(3), UTC)
    clean = Spec(rate_hz=100.0, angle_noise_rad=0.0, claimed_sigma_rad=0.005).simulate(
        tr, np.random.default_rng(3), UTC)
    assert np.diff(d.time_s).min() == pytest.approx(0.02)
    err = attitude.wrap_pi(d.z[:, 0] - clean.z[:, 0])
    assert err.std() == pytest.approx(0.005 / np.sqrt(2), rel=0.06)
    assert d.sigma[0, 0] == pytest.approx(0.005 / np.sqrt(2), rel=1e-12)


def test_filter_model_residual_and_jacobian():
    att = np.array([0.05, -0.08, 1.2])  # a rolling, pitching ship
    lla = START
    nav = strapdown.make_nav(lla, np.array([3.0, 4.0, 0.0]), attitude.euler_to_quat(att))
    s = _sun(18.0, 120.0)
    C = attitude.euler_to_dcm(att)
    img = images(C, s, np.deg2rad(20.0))
    beta = np.arctan2(img[0, 1] - img[2, 1], img[0, 0] - img[2, 0])
    row = np.array([beta, *s, 0.0, 0.005, 0, 0, 0, 0])
    par = np.array([np.deg2rad(20.0)])
    model = get("neutral_point")

    def call(n):
        z, H, R = np.zeros(1), np.zeros((1, 15)), np.zeros(1)
        m = model.kernel(n, np.ascontiguousarray(attitude.quat_to_dcm(n[0:4])), np.zeros(6),
                         row, par, 0.0, z, H, R, np.zeros(1, np.int64))
        return m, z, H, R

    m, z, H, R = call(nav)
    assert m == 1 and abs(z[0]) < 1e-9 and R[0] == pytest.approx(0.005**2)
    num = np.zeros(3)
    for j in range(3):
        dx = np.zeros(9)
        dx[j] = 1e-5
        num[j] = (call(_perturbed(nav, dx))[1][0] - call(_perturbed(nav, -dx))[1][0]) / 2e-5
    np.testing.assert_allclose(H[0, :3], num, atol=1e-5)
    assert abs(H[0, 2]) == pytest.approx(1.0, abs=0.05)  # beta turns with the heading
    assert default_rows is not None
