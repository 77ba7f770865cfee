"""Skylight-polarization compass: heading (and pitch) residuals against the INS.

Data row (:mod:`fuzzynav.sim.sensors.polarization`): ``[aop_1..aop_k, sun_e, sun_n, sun_u,
sigma_1..sigma_k, 0, 0, 0]``, and for an imaging sensor the AoPs' cosines and sines, the sun's
azimuth, its body direction from the AoPs and the views used: what the fit needs from the data alone,
computed once per recording (:mod:`fuzzynav.filters.measurements.polarization_rows`).
Parameters: ``[sensor_type, k, mode, prior_pitch_std, prior_heading_std, frames (k x 9)]``,
the frames (view direction and the reference axes of its AoP,
:func:`~fuzzynav.nav.polarization_imaging.view_frames`) computed once per run.

Modes
-----
``angles`` (default, as the papers do): the sensor's AoPs are converted into attitude angles
with the INS prediction resolving the 180° ambiguity, and the filter sees

* point (zenith) sensor: ``z = heading_ins - heading_pol`` with
  ``H = dpsi/dphi - (dpsi_pol/dpitch) dpitch/dphi - (dpsi_pol/droll) droll/dphi`` — the
  conversion uses the INS tilt, whose error therefore enters the converted heading;
  ``R = (dheading/daop)^2 sigma_aop^2``;
* imaging sensor: pitch and heading (roll taken from the INS, as in paper 000, which does
  not estimate it); the solution moves with the INS roll error, so the rows carry
  ``- d(solution)/d(roll) droll/dphi`` (implicit differentiation of the least-squares fit);
  the 2x2 covariance is decorrelated (the heading row conditioned on the pitch row) so that
  ``R`` stays diagonal.

``aop``: the raw angles of polarization, ``z_i = aop_pred_i(INS) - aop_i`` (folded mod pi)
with the exact Jacobian on the attitude error — no conversion, no ambiguity beyond the
E-vector sign.

Channels: ``heading``, ``pitch``, ``aop``.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters.layout import X_ATT
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.nav import polarization_solver as ps
from fuzzynav.nav.attitude import mod_pos, wrap_pi
from fuzzynav.nav.polarization_geometry import TWO_PI, fold_half_pi
from fuzzynav.filters.measurements.polarization_rows import fill_extra, rows
from fuzzynav.nav.polarization_imaging import FRAME, imaging_fit_sun, view_frames

__all__ = ["MODES", "euler_jacobian", "euler_rows", "polarization_kernel", "MODEL"]

MODES = {"angles": 0, "aop": 1}
CH_HEADING, CH_PITCH, CH_AOP = 0, 1, 2
#: largest attitude variance an imaging fix may claim and still be used [rad^2] (~6 deg)
_MAX_VAR = 0.01
_HDR = 5


@nb.njit(cache=True, error_model="numpy")
def euler_jacobian(C, J):
    """Rows d(pitch, roll, heading)/d(phi) of ``C_bn`` for ``C_calc = (I - [phi x]) C``."""
    jp, jr, jh = euler_rows(C)
    for j in range(3):
        J[0, j], J[1, j], J[2, j] = jp[j], jr[j], jh[j]


@nb.njit(cache=True, error_model="numpy")
def euler_rows(C):
    """:func:`euler_jacobian` as three 3-tuples (pitch, roll, heading rows): no array."""
    cp2 = C[0, 1] ** 2 + C[1, 1] ** 2  # cos^2 pitch
    cp = math.sqrt(cp2)
    jp = (-C[1, 1] / cp, C[0, 1] / cp, 0.0)
    jr = ((C[2, 2] * C[1, 0] - C[2, 0] * C[1, 2]) / cp2,
          (C[2, 0] * C[0, 2] - C[2, 2] * C[0, 0]) / cp2, 0.0)
    jh = (-C[2, 1] * C[0, 1] / cp2, -C[2, 1] * C[1, 1] / cp2, 1.0)
    return jp, jr, jh


@nb.njit(cache=True, error_model="numpy")
def _euler(C):
    pitch = math.asin(max(-1.0, min(1.0, C[2, 1])))
    roll = math.atan2(-C[2, 0], C[2, 2])
    heading = mod_pos(math.atan2(C[0, 1], C[1, 1]), TWO_PI)
    return pitch, roll, heading


@nb.njit(cache=True, error_model="numpy")
def _point(C, aop, sun, sigma, J, z, H, R, chan):
    pitch, roll, heading = _euler(C)
    h, dh_da = ps.heading_from_zenith_aop(aop, sun, pitch, roll, heading)
    if not (math.isfinite(h) and math.isfinite(dh_da)):
        return 0
    dp, dr = ps.zenith_heading_tilt_partials(sun, pitch, roll, h)
    if not (math.isfinite(dp) and math.isfinite(dr)):
        return 0  # the two heading roots coincide: the conversion is singular here
    euler_jacobian(C, J)
    z[0] = wrap_pi(heading - h)
    for j in range(3):
        H[0, X_ATT + j] = J[2, j] - dp * J[0, j] - dr * J[1, j]
    R[0] = (dh_da * sigma) ** 2
    chan[0] = CH_HEADING
    return 1


@nb.njit(cache=True, error_model="numpy")
def _imaging(C, aops, extra, frames, sun, sigma, prior_std, z, H, R, chan):
    k = aops.size  # extra: the row's columns from polarization_rows
    pitch, roll, heading = _euler(C)
    p, h, c00, c01, c11, _, dp_dr, dh_dr = imaging_fit_sun(
        aops, extra[:2 * k], frames, sun, extra[2 * k], extra[2 * k + 1], extra[2 * k + 2],
        extra[2 * k + 3], int(extra[2 * k + 4]), roll, pitch, heading, prior_std[0],
        prior_std[1], sigma)
    if not (math.isfinite(p) and math.isfinite(h)):
        return 0
    if not (math.isfinite(dp_dr) and math.isfinite(dh_dr)):
        return 0
    jp, jr, jh = euler_rows(C)
    # rows as seen through the solver: d(angle) - d(solution)/d(roll) d(roll)
    jp = (jp[0] - dp_dr * jr[0], jp[1] - dp_dr * jr[1], jp[2] - dp_dr * jr[2])
    jh = (jh[0] - dh_dr * jr[0], jh[1] - dh_dr * jr[1], jh[2] - dh_dr * jr[2])
    dh = wrap_pi(heading - h)
    if not (0.0 < c00 < _MAX_VAR) or not (0.0 < c11 < _MAX_VAR):
        # degenerate geometry (views nearly in one plane with the sun): keep at most the
        # heading row when it alone is well determined
        if not 0.0 < c11 < _MAX_VAR:
            return 0
        z[0] = dh
        for j in range(3):
            H[0, X_ATT + j] = jh[j]
        R[0] = c11
        chan[0] = CH_HEADING
        return 1
    g = c01 / c00  # heading row conditioned on the pitch row
    r1 = c11 - g * c01
    if not r1 > 1e-6 * c11:
        return 0
    z[0] = pitch - p
    z[1] = dh - g * z[0]
    for j in range(3):
        H[0, X_ATT + j] = jp[j]
        H[1, X_ATT + j] = jh[j] - g * jp[j]
    R[0] = c00
    R[1] = r1
    chan[0], chan[1] = CH_PITCH, CH_HEADING
    return 2


@nb.njit(cache=True, error_model="numpy")
def _raw(C, aops, frames, sun, sigmas, z, H, R, chan):
    m = 0
    for i in range(aops.size):
        if not (math.isfinite(aops[i]) and sigmas[i] > 0.0):
            continue
        pred, jac = ps.aop_attitude_jacobian(C, frames[FRAME * i:FRAME * i + 3], sun)
        if not math.isfinite(pred):
            continue
        z[m] = fold_half_pi(pred - aops[i])
        for j in range(3):
            H[m, X_ATT + j] = jac[j]
        R[m] = sigmas[i] ** 2
        chan[m] = CH_AOP
        m += 1
    return m


@njit_signature(MEAS_SIG)
def polarization_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    kind, k, mode = int(par[0]), int(par[1]), int(par[2])
    frames = par[_HDR:_HDR + FRAME * k]  # a view of the parameters: nothing copied
    aops = row[0:k]
    sun = row[k:k + 3]
    sig = row[k + 3:2 * k + 3]
    if mode == 1:
        return _raw(C_bn, aops, frames, sun, sig, z, H, R, chan)
    if kind == 0:
        if not (math.isfinite(aops[0]) and sig[0] > 0.0):
            return 0
        J = np.empty((3, 3))
        return _point(C_bn, aops[0], sun, sig[0], J, z, H, R, chan)
    extra = row[2 * k + 6:4 * k + 11]
    # a row without polarization_rows' columns (or zero-padded: no view counted) forms them
    if extra.size < 2 * k + 5 or extra[2 * k + 4] == 0.0:
        extra = np.empty(2 * k + 5)
        fill_extra(aops, sun, frames, extra)
    return _imaging(C_bn, aops, extra, frames, sun, sig[0], par[3:5], z, H, R, chan)


def _pack(data, options) -> np.ndarray:
    views = np.asarray(data.meta.get("views_b", [[0.0, 0.0, 1.0]]), float).reshape(-1, 3)
    mode = options.get("mode", "angles")
    if mode not in MODES:
        from fuzzynav.errors import UnknownNameError

        raise UnknownNameError("polarization measurement mode", mode, MODES)
    prior = np.deg2rad(options.get("prior_std_deg", (5.0, 10.0)))
    return np.concatenate([[float(data.meta.get("sensor_type", 0)), views.shape[0],
                            MODES[mode], *prior], view_frames(np.ascontiguousarray(views))])


MODEL = register(MeasurementModel(kind="polarization", kernel=polarization_kernel,
                                  max_rows=9, channels=("heading", "pitch", "aop"), pack=_pack,
                                  rows=rows))
