"""Motion-state and receiver-quality inputs of a rule file's binding (epoch context)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation import context
from fuzzynav.filters.adaptation.r_scaling import FuzzyRScaling
from fuzzynav.filters.runner import InitialState, run_filter
from fuzzynav.fuzzy.io import from_dict
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.trajectory import Segment, generate
from tests.filters.simple_data import CONFIG, START, gnss_fixes

OMEGA_IE = 7.292115e-5  # WGS-84 earth rate [rad/s]


def probe(stats):
    """An r-scaling rule file whose inputs read ``stats`` ({name: (statistic, range)}) and
    whose one rule holds the R factor at 1: the loop logs the inputs (the first two)."""
    wide = lambda lo, hi: [lo - (hi - lo), lo, hi, hi + (hi - lo)]  # noqa: E731
    doc = {"format": "fuzzynav-fis", "version": 1, "name": "probe", "type": "mamdani",
           "operators": {"and": "min", "or": "max", "implication": "min",
                         "aggregation": "max", "defuzzifier": "centroid"},
           "inputs": [{"name": n, "range": list(r), "terms": [
               {"name": "any", "mf": "trap", "params": wide(*r)}]} for n, (_, r) in
               stats.items()],
           "outputs": [{"name": "t", "range": [0.5, 1.5], "default": 1.0, "terms": [
               {"name": "one", "mf": "tri", "params": [0.5, 1.0, 1.5]}]}],
           "rules": [{"if": {next(iter(stats)): "any"}, "then": {"t": "one"}}],
           "binding": {"adapter": "r-scaling", "outputs": {"t": "r_scale"},
                       "inputs": {n: {"statistic": s} for n, (s, _) in stats.items()}}}
    return FuzzyRScaling(from_dict(doc), "probe.json")


def logged(res, name):
    """Per-epoch values of diag column ``name`` of the gnss stream."""
    ev = res.events["gnss"]
    return ev.diag[:, ev.diag_names.index(name)]


def test_fill_and_statistics_follow_their_definitions():
    M, W = 4, 3
    ctx = np.zeros(context.size(M, W))
    ctx[context.CTX_M] = M
    g = earth.gravity(START[0], START[2])
    nav = np.zeros(16)
    from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_VEL
    nav[NAV_LAT], nav[NAV_H] = START[0], START[2]
    nav[NAV_VEL:NAV_VEL + 3] = (3.0, 4.0, 0.0)
    aux = np.array([0.0, 0.06, 0.08, 0.0, 3.0, g + 1.0])
    R = np.array([1.0, 9.0, 4.0, 99.0])
    context.fill(ctx, nav, aux, R, 3, np.array([7.0, 1.0, 12.0]))
    chan = np.array([0, 0, 1], np.int64)
    assert context.statistic(4, ctx, chan, 3, -1) == pytest.approx(5.0)
    assert context.statistic(5, ctx, chan, 3, -1) == pytest.approx(0.1 / units.DPS)
    assert context.statistic(6, ctx, chan, 3, -1) == pytest.approx(math.hypot(3.0, g + 1) - g)
    assert context.statistic(7, ctx, chan, 3, 0) == pytest.approx(math.sqrt(5.0))  # (1+9)/2
    assert context.statistic(7, ctx, chan, 3, -1) == pytest.approx(math.sqrt(14.0 / 3.0))
    assert context.statistic(8, ctx, chan, 3, 2) == 12.0  # data-row column 2


def _turntable(w_rad_s, seconds=60.0, rate_hz=100.0):
    """A level IMU at rest on the ground spinning at ``w`` about the vertical: exact
    increments (the earth rate included), and GNSS fixes of the fixed point."""
    n = int(seconds * rate_hz)
    t = np.arange(n + 1) / rate_hz
    lat, h = START[0], START[2]
    tm = 0.5 * (t[:-1] + t[1:])
    # the earth rate's horizontal part (north) turns in the spinning body frame
    wn, wu = OMEGA_IE * math.cos(lat), OMEGA_IE * math.sin(lat)
    rate = np.column_stack([wn * np.sin(w_rad_s * tm), wn * np.cos(w_rad_s * tm),
                            np.full(n, w_rad_s + wu)])
    g = earth.gravity(lat, h)
    imu = SimpleNamespace(time_s=t, dtheta_b=rate / rate_hz,
                          dv_b=np.tile([0.0, 0.0, g / rate_hz], (n, 1)))
    k = np.arange(0, n + 1, int(rate_hz))
    z = np.column_stack([np.full((k.size, 3), START), np.zeros((k.size, 3))])
    gnss = SensorData("gnss", t[k], z, np.tile([1.0, 1.0, 2.0, 0.05, 0.05, 0.1], (k.size, 1)))
    init = InitialState(0.0, START.copy(), np.zeros(3), attitude.dcm_to_quat(np.eye(3)))
    return imu, gnss, init, math.hypot(w_rad_s + wu, wn)


def test_a_constant_rate_turn_gives_that_rate_and_rest_gives_zero_force_deviation():
    imu, gnss, init, expect = _turntable(10.0 * units.DPS)
    pol = probe({"rate": ("angular_rate", (0.0, 20.0)),
                 "force": ("force_deviation", (-1.0, 1.0))})
    res = run_filter(imu, {"gnss": gnss}, init, CONFIG, adapters={"gnss": pol})
    rate, force = logged(res, "rate")[1:], logged(res, "force")[1:]
    # deg/s at the edge; the filter's gyro-bias estimate (P0 20 deg/h) may shift it a little
    np.testing.assert_allclose(rate, expect / units.DPS, atol=0.01)
    np.testing.assert_allclose(force, 0.0, atol=0.01)  # |f| = g at rest (accel P0 500 ug)


def test_speed_in_a_straight_cruise_is_the_cruise_speed():
    tr = generate(START, [Segment("cruise", 30)], 100.0, 12.0, 0.3)
    imu = SimpleNamespace(time_s=tr.time_s, dtheta_b=tr.dtheta_b, dv_b=tr.dv_b)
    init = InitialState(0.0, tr.lla[0], tr.vel_n[0], attitude.dcm_to_quat(
        attitude.euler_to_dcm(tr.att[0])))
    # noiseless fixes: the estimated speed (which the statistic reads) is the true one
    gnss = gnss_fixes(tr, np.random.default_rng(0), np.zeros(3), np.zeros(3))
    pol = probe({"v": ("speed", (0.0, 30.0)), "rate": ("angular_rate", (0.0, 5.0))})
    res = run_filter(imu, {"gnss": gnss}, init, CONFIG, adapters={"gnss": pol})
    np.testing.assert_allclose(logged(res, "v"), 12.0, atol=0.005)
    np.testing.assert_allclose(logged(res, "rate")[1:], 0.0, atol=0.01)


def _quality_run(meta):
    imu, gnss, init, _ = _turntable(0.0, seconds=6.0)
    gnss = SensorData("gnss", gnss.time_s, gnss.z, gnss.sigma, meta)
    pol = probe({"q": ("fix_type", (1.0, 6.0)), "ns": ("n_sat", (0.0, 30.0))})
    return run_filter(imu, {"gnss": gnss}, init, CONFIG, adapters={"gnss": pol})


def test_receiver_quality_inputs_read_the_recordings_columns():
    q = np.array([1, 2, 2, 5, 1, 1, 6], float)
    ns = np.array([12, 11, 9, 5, 13, 14, 10], float)
    res = _quality_run({"q": q, "ns": ns})
    np.testing.assert_array_equal(logged(res, "q"), q)
    np.testing.assert_array_equal(logged(res, "ns"), ns)


def test_receiver_quality_inputs_are_refused_on_data_without_them():
    with pytest.raises(InputFileError, match=r"probe\.json.*\$\.binding\.inputs\.q\.statistic"
                                             r".*carry no 'fix_type'"):
        _quality_run({})


def test_motion_statistics_take_no_channel():
    doc_pol = probe({"v": ("speed", (0.0, 30.0))})
    doc = doc_pol.fis.binding | {"inputs": {"v": {"statistic": "speed", "channel": "pos"}}}
    from dataclasses import replace
    with pytest.raises(InputFileError, match=r"inputs\.v\.channel.*not a per-channel"):
        FuzzyRScaling(replace(doc_pol.fis, binding=doc), "probe.json")


def test_a_recording_carries_fix_type_and_satellite_count_to_the_gnss_rows(rtklib_drive):
    from fuzzynav.filters import measurements
    from fuzzynav.realdata.loaders.rtklib import load_rtklib

    rec = load_rtklib(rtklib_drive, span_s=(0.0, 60.0))
    rows = measurements.get("gnss").rows(rec.gnss)
    cols = dict(measurements.get("gnss").quality)
    # RTKLIB's Q and ns columns of the .pos file, epoch by epoch
    np.testing.assert_array_equal(rows[:, cols["fix_type"]], rec.gnss.meta["q"])
    np.testing.assert_array_equal(rows[:, cols["n_sat"]], rec.gnss.meta["ns"])
    assert set(np.unique(rows[:, cols["fix_type"]])) <= {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}


def test_the_recording_template_binds_to_a_recording_and_not_to_simulated_fixes(rtklib_drive):
    from fuzzynav.filters import measurements
    from fuzzynav.filters.adaptation.rq_scaling import FuzzyRQScaling
    from fuzzynav.fuzzy import load_fis
    from fuzzynav.realdata.loaders.rtklib import load_rtklib

    path = "rules/recording_rq_quality_gnss.json"
    pol, model = FuzzyRQScaling(load_fis(path), path), measurements.get("gnss")
    rec = load_rtklib(rtklib_drive, span_s=(0.0, 60.0))
    pol.bind(model, model.rows(rec.gnss))  # Q and ns are there
    sim = SensorData("gnss", rec.gnss.time_s, rec.gnss.z, rec.gnss.sigma)
    with pytest.raises(InputFileError, match=r"inputs\.fix\.statistic.*carry no 'fix_type'"):
        pol.bind(model, model.rows(sim))
