"""The worked example of docs/architecture.md, "Adding a sensor with its measurement model".

A barometric altimeter: the residual INS minus sensor ``z = h_ins - h_baro`` and its row of
``H`` (1 on the up-position error).  The kernel is checked against finite differences of the
navigation state in the default run; registering it and running the filter recompiles the
loop for one more kernel (a minute), so that part is marked slow.
"""
import math

import numba as nb
import numpy as np
import pytest

from fuzzynav.filters.layout import X_POS
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.filters.runner import run_filter
from fuzzynav.nav import attitude, strapdown
from fuzzynav.nav.state_layout import NAV_H, NAV_VEL
from fuzzynav.sim.sensors import SensorData
from tests.filters.simple_data import CONFIG, run_inputs, trajectory
from tests.filters.test_measurements import ATT, LLA, VEL, _call, _numeric_H

BARO_SIGMA = 0.3  # m


@nb.njit(MEAS_SIG, cache=True)
def baro_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    """Data row ``[h_m, sigma_m]``; ``z = h_ins - h_baro`` at the measurement time."""
    if not (math.isfinite(row[0]) and row[1] > 0.0):
        return 0
    z[0] = nav[NAV_H] - nav[NAV_VEL + 2] * dt_back - row[0]
    H[0, X_POS + 2] = 1.0  # the up component of the position error (ENU metres)
    R[0] = row[1] * row[1]
    chan[0] = 0
    return 1


def _pack(data, options):
    return np.zeros(1)  # no constants (a lever arm or an offset would go here)


# a sensor module registers this at import: register(BARO)
BARO = MeasurementModel(kind="test_baro", kernel=baro_kernel, max_rows=1,
                        channels=("height",), pack=_pack)


def test_baro_residual_and_jacobian():
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(ATT))
    row = np.array([LLA[2], BARO_SIGMA])
    m, z, H, R, chan = _call(BARO, nav, row, np.zeros(1))
    assert m == 1 and z[0] == pytest.approx(0.0, abs=1e-9) and R[0] == BARO_SIGMA**2
    Hn = _numeric_H(BARO, nav, row, np.zeros(1), m, [1e-6] * 3 + [1e-3] * 3 + [1e-1] * 3)
    np.testing.assert_allclose(H[:, :9], Hn, atol=1e-6)


@pytest.mark.slow
def test_baro_in_the_filter_tightens_the_height():
    register(BARO)
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, seed=11)
    t = tr.time_s[::10]
    rng = np.random.default_rng(12)
    baro = SensorData("test_baro", t, (tr.lla[::10, 2] + rng.normal(0, BARO_SIGMA, t.size))[:, None],
                      np.full((t.size, 1), BARO_SIGMA))
    without = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    with_baro = run_filter(imu, {"gnss": gnss, "baro": baro}, init, CONFIG)
    assert with_baro.ok and with_baro.events["baro"].accepted.all()
    late = with_baro.time_s > 60.0
    # 10 Hz at 0.3 m against 1 Hz GNSS at 2 m: the height sigma must drop well below
    assert np.all(with_baro.state_sigma("pos")[late, 2] < 0.5 * without.state_sigma("pos")[late, 2])
    err = with_baro.lla[:, 2] - np.interp(with_baro.time_s, tr.time_s, tr.lla[:, 2])
    assert np.mean(np.abs(err[late]) < 3 * with_baro.state_sigma("pos")[late, 2]) > 0.95
