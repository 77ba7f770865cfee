"""The worked example of docs/architecture.md, "Adding an adaptation policy".

A Huber-like innovation gate in one class: a row whose innovation is larger than ``c`` of
its predicted sigmas gets its measurement variance inflated, ``R -> k R``, just enough that
``r^2 = c^2 (H P- H^T + k R)`` -- the outlier still updates, with the weight of a
``c``-sigma residual.  The kernel is checked against that closed form in the default run;
registering it and running the filter recompiles the loop for one more kernel table entry
(about a minute), so that part is marked slow.
"""
import dataclasses

import numba as nb
import numpy as np
import pytest

from fuzzynav.filters.adaptation import ADAPT_SIG, N_DIAG, Adapter, register
from fuzzynav.filters.runner import run_filter
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from tests.filters.simple_data import CONFIG, run_inputs, trajectory


@nb.njit(ADAPT_SIG, cache=True)
def nis_inflate_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    """``fp[0]`` = c; ``out[2 + i]`` = max(1, (r_i^2 / c^2 - HPH_ii) / R_i)."""
    c2 = fp[0] * fp[0]
    out[0] = 1.0  # predicted covariance untouched
    out[1] = 1.0  # process noise untouched
    worst = 1.0
    for i in range(m):
        k = max(1.0, (r[i] * r[i] / c2 - HPH[i, i]) / R[i])
        out[2 + i] = k
        worst = max(worst, k)
    diag[0] = worst  # logged per epoch in the sensor's EventLog
    st[0] += worst > 1.0  # state kept across epochs: how many epochs were inflated
    return 0


class NisInflate(Adapter):
    """Inflate ``R`` of rows beyond ``c`` predicted sigmas (immutable configuration)."""

    name = "test-nis-inflate"
    kernel = nis_inflate_kernel
    diag_names = ("k_max",)

    def __init__(self, c: float = 3.0):
        self.c = float(c)

    def arrays(self, model):
        return np.array([self.c]), np.zeros(1, dtype=np.int64), np.zeros(1)


def _call(c, r, hph, R):
    m = len(r)
    out, diag, st = np.zeros(2 + m), np.zeros(N_DIAG), np.zeros(1)
    status = nis_inflate_kernel(np.array([c]), np.zeros(1, np.int64), st, np.array(r, float),
                                np.diag(np.array(hph, float)), np.array(R, float),
                                np.zeros(m, np.int64), m, out, diag, np.zeros(1))
    return status, out, diag, st


def test_the_kernel_meets_the_closed_form():
    r, hph, R = [10.0, 1.0, -7.0], [1.0, 1.0, 0.5], [1.0, 1.0, 2.0]
    status, out, diag, st = _call(3.0, r, hph, R)
    k = out[2:]
    assert status == 0 and out[0] == 1.0 and out[1] == 1.0
    assert k[1] == 1.0  # an inlier keeps its R
    r2, hph, R = np.square(r), np.array(hph), np.array(R)
    # the outliers are left exactly c = 3 sigmas out after the inflation
    np.testing.assert_allclose(r2[[0, 2]] / (hph + k * R)[[0, 2]], 9.0, rtol=1e-12)
    assert diag[0] == k.max() and st[0] == 1.0


@pytest.mark.slow
def test_the_policy_in_the_filter_rides_out_gnss_outliers():
    register(NisInflate)
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, seed=21)
    z = gnss.z.copy()
    z[5::15, 0] += 60.0 / 6.4e6  # every 15th fix 60 m north: 30 sigma
    bad = dataclasses.replace(gnss, z=z)
    plain = run_filter(imu, {"gnss": bad}, init, CONFIG)
    gated = run_filter(imu, {"gnss": bad}, init, CONFIG, {"gnss": NisInflate(3.0)})
    err = {n: rms_metrics(errors_vs_trajectory(res, tr))["rms_pos_h_m"]
           for n, res in (("plain", plain), ("gated", gated))}
    assert gated.ok and err["gated"] < 0.5 * err["plain"]
    assert gated.events["gnss"].diag_names[0] == "k_max"
    assert (gated.events["gnss"].diag[:, 0] > 1.0).sum() >= len(z[5::15]) - 1
    # with a gate nobody reaches, the policy changes nothing (the same loop arithmetic)
    off = run_filter(imu, {"gnss": bad}, init, CONFIG, {"gnss": NisInflate(1e12)})
    np.testing.assert_allclose(off.lla, plain.lla, rtol=0, atol=1e-12)
