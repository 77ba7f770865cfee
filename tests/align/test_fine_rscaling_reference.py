"""The fuzzy alignment filter against paper 002's rule written out independently.

The alignment steps the package's one R-scaling policy (the compiled ``r-scaling`` kernel,
through ``EpochPolicy``): ``R(k) = s(k) R0``, ``s(k) = t(k) s(k-1)`` kept in the alignment's
bounds, ``t = 1`` until the window is full.  Here the paper's form is written the obvious
way -- ``R(k) = t(k) R(k-1)``, ``ROR = mean_M(r^T r) / tr(H P- H^T + R(k-1))``, the rule
file evaluated by the engine's own numpy ``evaluate`` (not the compiled kernel) -- and the
two runs must agree.  They are the same sums in another order (the window's running sums,
``s R0`` against ``t R(k-1)``), so they agree to rounding, not bit for bit: on paper002
seeds 0-2 the metrics moved by at most 1.8e-12 relative when the alignment moved onto the
shared policy; the tolerance below is that with room.
"""
import dataclasses
from collections import deque

import numpy as np

from fuzzynav.align import alignment_run as R
from fuzzynav.align.fine import DEFAULT_RULES, SCALE_BOUNDS, r_policy, run_fine
from fuzzynav.align.model import measurement_matrix, transition
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.filters.catalog import find_rule_file
from fuzzynav.filters.reference import predict, update
from fuzzynav.fuzzy import load_fis

#: relative agreement of the two forms (rounding only; see the module docstring)
RTOL = 1e-9


def _paper_form(ep, layout, noise, fis):
    """Paper 002's fuzzy alignment KF, written independently of the package's policy."""
    H, R0, Qd = measurement_matrix(layout), noise.r0(layout), noise.qd(layout)
    window, lo, hi = fis.binding["window"], *SCALE_BOUNDS
    name_in, name_out = fis.inputs[0].name, fis.outputs[0].name
    x, P, Rk, scale = np.zeros(layout.n), noise.p0(layout), R0.copy(), 1.0
    buf = deque(maxlen=window)
    Phis = transition(layout, ep.C_bn[:-1], ep.f_n[1:], ep.lat_rad, noise.period_s)
    xs = [x]
    for k in range(1, ep.time_s.size):
        x, P = predict(x, P, Phis[k - 1], Qd)
        z = ep.vel_n[k, :H.shape[0]]
        r = z - H @ x
        buf.append(float(r @ r))
        t = 1.0
        if len(buf) == window:
            ror = np.mean(buf) / np.trace(H @ P @ H.T + Rk)
            t = float(fis.evaluate({name_in: ror})[name_out])
            t = min(max(t, lo / scale), hi / scale)
        scale *= t
        Rk = t * Rk
        x, P = update(x, P, z, H, Rk)
        xs.append(x)
    return np.array(xs), P


def test_the_fuzzy_alignment_filter_is_paper_002s_rule():
    scn = load_alignment_scenario("paper002-rmismatch")
    scn = dataclasses.replace(scn, duration_s=300.0,
                              imu=dataclasses.replace(scn.imu, rate_hz=10.0))
    log = R.simulate(scn, 1)
    ep = R.epochs(scn, log, 1)
    layout = R.get_align_filter("align-fuzzy").layout
    got = run_fine(ep, layout, scn.noise, policy=r_policy())
    x_ref, P_ref = _paper_form(ep, layout, scn.noise, load_fis(find_rule_file(DEFAULT_RULES)))
    assert np.max(got.r_scale) > 4.0  # the scaling acted (R0 is 4x too small here)
    scale = np.max(np.abs(x_ref), axis=0)
    np.testing.assert_allclose(got.x / scale, x_ref / scale, rtol=0, atol=RTOL)
    np.testing.assert_allclose(got.P[-1], P_ref, rtol=RTOL, atol=0)
