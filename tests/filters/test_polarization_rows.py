"""The imaging rows' data-only columns: what the fit would compute at each epoch, kept per
measurement array and never read stale."""
import gc
import math

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.measurements import polarization_rows as pr
from fuzzynav.nav import polarization_imaging as pim
from fuzzynav.sim import skylight as sk
from fuzzynav.sim.sensors import SensorData

VIEWS = sk.view_direction(np.radians([0, 30, 30, 30, 30, 30, 30]),
                          np.radians([0, 0, 60, 120, 180, 240, 300]))
K = VIEWS.shape[0]


def _imaging_data(seed=0, epochs=40):
    rng = np.random.default_rng(seed)
    aops = rng.uniform(-np.pi / 2, np.pi / 2, (epochs, K))
    aops[rng.random((epochs, K)) < 0.2] = np.nan  # views below the DoP threshold
    aops[0, 1:] = np.nan  # one view only: no sun direction
    sun = rng.normal(size=(epochs, 3))
    sun /= np.linalg.norm(sun, axis=1, keepdims=True)
    z = np.hstack([aops, sun])
    sigma = np.hstack([np.full((epochs, K), 0.01), np.zeros((epochs, 3))])
    return SensorData("polarization", np.arange(epochs, dtype=float), z, sigma,
                      {"sensor_type": 1, "views_b": VIEWS})


def test_columns_are_the_fits_own_per_epoch_values():
    data = _imaging_data()
    rows = pr.rows(data)
    start = pr.extra_start(K)
    assert rows.shape == (40, start + pr.extra_columns(K))
    np.testing.assert_array_equal(rows[:, :start], np.hstack([data.z, data.sigma]))
    frames = pim.view_frames(VIEWS)
    for e in range(rows.shape[0]):
        aops, extra = data.z[e, :K], rows[e, start:]
        trig = pim.aop_trig(aops)
        # the same kernels on the same inputs, called from another compiled function
        np.testing.assert_allclose(extra[:2 * K], trig, rtol=0, atol=1e-15)
        assert abs(extra[2 * K] - math.atan2(data.z[e, K + 1], data.z[e, K])) < 1e-15
        sx, sy, sz, used = pim.sun_from_aops(aops, trig, frames)
        assert extra[2 * K + 4] == used == np.count_nonzero(~np.isnan(aops))
        np.testing.assert_allclose(extra[2 * K + 1:2 * K + 4], (sx, sy, sz), rtol=0, atol=1e-15)
    assert np.isnan(rows[0, start + 2 * K + 1])  # a single view fixes no sun direction


def test_kept_while_the_array_lives_and_recomputed_when_changed_in_place():
    data = _imaging_data(1)
    first = pr.imaging_columns(data.z, VIEWS)
    assert pr.imaging_columns(data.z, VIEWS) is first  # the second run reads it
    assert not first.flags.writeable
    data.z[3, 2] += 0.1  # changed in place: the kept columns are stale now
    fresh = pr.imaging_columns(data.z, VIEWS)
    assert fresh is not first and fresh[3, 2] != first[3, 2]
    assert pr.imaging_columns(data.z, VIEWS[::-1].copy()) is not fresh  # other views
    key = id(data.z)
    assert data.z in pr._KEPT
    del data, first, fresh
    gc.collect()
    assert key not in pr._KEPT._entries  # the entry left with its array


def test_point_sensor_rows_carry_no_extra_columns():
    data = _imaging_data(2)
    point = SensorData("polarization", data.time_s, data.z[:, [0, K, K + 1, K + 2]],
                       data.sigma[:, [0, K, K + 1, K + 2]], {"sensor_type": 0})
    np.testing.assert_array_equal(pr.rows(point), np.hstack([point.z, point.sigma]))


def test_views_that_do_not_match_the_aop_columns_are_refused_with_the_shapes():
    """A stream whose views_b names more views than z has AoP columns would make the kernel
    read past its rows: one clear error names both shapes instead."""
    data = _imaging_data(3)
    wrong = SensorData("polarization", data.time_s, data.z[:, 2:], data.sigma[:, 2:],
                       data.meta)
    with pytest.raises(FuzzynavError, match=r"z has shape \(40, 8\).*names 7 views"):
        pr.rows(wrong)
