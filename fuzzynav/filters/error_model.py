"""Error-state model of the ENU strapdown INS (numba kernels).

The state vector is a :class:`~fuzzynav.filters.layout.StateLayout`: the core ``att`` (phi_n,
``C_bn_calc = (I - [phi x]) C_bn_true``), ``vel`` and ``pos`` (calc - true, ENU metres),
then the sensor-error blocks of :class:`ErrorModel`: every gyro block adds to the residual
gyro bias [rad/s], every accelerometer block to the residual accelerometer bias [m/s^2],
other registered blocks (e.g. ``mag_bias``) only enter measurement models; a block is a
random constant (tau = inf) or a first-order Gauss-Markov process with correlation time tau.

The dynamics are the classical phi-angle model (Savage; Yan Gongmin's PSINS ``etm``) written
with the position error in metres: with ``D = diag((R_N+h) cos L, R_M+h, 1)`` the metric
error is ``D [dlon, dlat, dh]`` and its system matrix ``D F D^-1 + dD/dt D^-1``.
Discretisation: ``Phi = I + F dt + (F dt)^2 / 2`` and
``Qd = Q dt + (F Q + Q F^T) dt^2 / 2 + F Q F^T dt^3 / 3`` (second-order Van Loan series).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numba as nb

from fuzzynav.filters import sized
from fuzzynav.filters.kalman import diagonal_tail, square_tail
from fuzzynav.filters.layout import (BLOCK_KINDS, CORE, COUPLE_ACCEL, COUPLE_GYRO, X_ATT,
                                     X_POS, X_VEL, StateLayout, kind_of)
from fuzzynav.nav.earth import E2, OMEGA_IE, gravity_sin_nb, radii_sin_nb
from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_VEL

__all__ = ["ErrorModel", "MODEL_15", "fill_F", "block_end", "discretize", "discretize_tail",
           "transition"]

# velocity error components, and the position error's rows/columns: in radians
# (dlat, dlon, dh) while F is formed, then ENU metres (dE, dN, dU) after _to_metric
_VE, _VN, _VU = X_VEL, X_VEL + 1, X_VEL + 2
_LAT, _LON, _HGT = X_POS, X_POS + 1, X_POS + 2
_E, _N = X_POS, X_POS + 1


def _numbered(kind, count):
    """Block names of ``count`` blocks of ``kind``: ``kind``, ``kind:1``, ``kind:2`` ..."""
    return [kind if i == 0 else f"{kind}:{i}" for i in range(count)]


@dataclass(frozen=True)
class ErrorModel:
    """The sensor-error blocks of the state and their dynamics.

    Parameters
    ----------
    gyro_tau_s : tuple of float
        One entry per gyro block: ``inf`` for a random constant, else the Gauss-Markov
        correlation time [s].
    accel_tau_s : tuple of float
        Same for the accelerometer blocks.
    extra : tuple of (name, tau_s)
        Further registered blocks (e.g. ``("mag_bias", inf)``), after the bias blocks.
    """

    gyro_tau_s: tuple = (math.inf,)
    accel_tau_s: tuple = (math.inf,)
    extra: tuple = ()

    def block_taus(self) -> dict:
        """Sensor block name -> tau [s], in state order."""
        out = dict(zip(_numbered("gyro_bias", len(self.gyro_tau_s)), self.gyro_tau_s))
        out.update(zip(_numbered("accel_bias", len(self.accel_tau_s)), self.accel_tau_s))
        out.update((str(nm), float(tau)) for nm, tau in self.extra)
        return out

    # the model is frozen, so what it derives is computed once per instance (a filter run
    # asks for the layout several times; cached_property stores it in the instance dict,
    # outside the fields that eq/hash/repr see)
    @cached_property
    def layout(self) -> StateLayout:
        """The state layout: the core, the gyro blocks, the accelerometer blocks, the extras."""
        return CORE.extended(*[(nm, BLOCK_KINDS.lookup(kind_of(nm)).size)
                               for nm in self.block_taus()])

    @cached_property
    def n_states(self) -> int:
        """Total number of error states."""
        return self.layout.n

    @cached_property
    def _block_arrays(self):
        inv = {nm: 0.0 if math.isinf(t) else 1.0 / t for nm, t in self.block_taus().items()}
        return self.layout.block_arrays(inv)

    def block_arrays(self):
        """``(start, coupling, inv_tau)`` arrays of the sensor blocks (for the loop; fresh
        writeable copies, as the compiled loop is typed for writeable arrays)."""
        return tuple(a.copy() for a in self._block_arrays)

    def labels(self):
        """State names for tables and plots."""
        return list(self.layout.labels())


#: the 15-state model (random-constant biases)
MODEL_15 = ErrorModel()


@nb.njit(cache=True, error_model="numpy")
def _dgravity_dlat(s, c):
    """Derivative of normal gravity with latitude [m/s^2/rad] (height factor neglected), from
    the sine and cosine of the latitude."""
    s2 = s * s
    w = 1.0 - E2 * s2
    ge, k = 9.7803253359, 0.00193185265241
    dg_du = ge * (k / math.sqrt(w) + 0.5 * E2 * (1.0 + k * s2) / (w * math.sqrt(w)))
    return dg_du * 2.0 * s * c


@nb.njit(cache=True, error_model="numpy")
def fill_F(F, nav, C_bn, f_n, blk_start, blk_kind, blk_inv_tau):
    """Write the continuous system matrix into ``F`` (n x n, overwritten).

    ``nav`` is the strapdown state, ``C_bn`` the (mean) attitude over the interval and
    ``f_n`` the mean specific force in the navigation frame.
    """
    F[:, :] = 0.0
    ve, vn, vu = nav[NAV_VEL], nav[NAV_VEL + 1], nav[NAV_VEL + 2]
    lat, h = nav[NAV_LAT], nav[NAV_H]
    sl, cl = math.sin(lat), math.cos(lat)  # once for the radii, gravity and the rates
    rm, rn = radii_sin_nb(sl)
    rmh, rnh = rm + h, rn + h
    tl = sl / cl
    wie_n, wie_u = OMEGA_IE * cl, OMEGA_IE * sl
    # omega_in = omega_ie + omega_en
    wie = (0.0, wie_n, wie_u)
    wen = (-vn / rmh, ve / rnh, ve * tl / rnh)
    win = (wen[0], wie_n + wen[1], wie_u + wen[2])
    # --- in radian position units (dlat, dlon, dh) first ---
    # d(omega_ie)/dp and d(omega_en)/dp
    # The three 3x3 blocks as row-major tuples (no heap allocation per call); zero entries
    # kept, so every sum below adds the same terms in the same order as with matrices.
    Mp1 = (0.0, 0.0, 0.0, -wie_u, 0.0, 0.0, wie_n, 0.0, 0.0)
    Mp2 = (0.0, 0.0, vn / rmh**2, 0.0, 0.0, -ve / rnh**2,
           ve / (rnh * cl * cl), 0.0, -ve * tl / rnh**2)
    Mav = (0.0, -1.0 / rmh, 0.0, 1.0 / rnh, 0.0, 0.0, tl / rnh, 0.0, 0.0)
    # attitude rows: phi' = -win x phi + Mav dv + (Mp1 + Mp2) dp - C_bn eps
    _skew_into(F, X_ATT, X_ATT, -win[0], -win[1], -win[2])
    for i in range(3):
        for j in range(3):
            F[X_ATT + i, X_VEL + j] = Mav[3 * i + j]
            F[X_ATT + i, X_POS + j] = Mp1[3 * i + j] + Mp2[3 * i + j]
    # velocity rows: dv' = f x phi + ([v x] Mav - [(2wie + wen) x]) dv + [v x](2Mp1 + Mp2) dp
    _skew_into(F, X_VEL, X_ATT, f_n[0], f_n[1], f_n[2])
    ax, ay, az = 2.0 * wie[0] + wen[0], 2.0 * wie[1] + wen[1], 2.0 * wie[2] + wen[2]
    for i in range(3):
        for j in range(3):
            vm = _skew_elem(ve, vn, vu, i, 0) * Mav[j] + \
                _skew_elem(ve, vn, vu, i, 1) * Mav[3 + j] + \
                _skew_elem(ve, vn, vu, i, 2) * Mav[6 + j]
            F[X_VEL + i, X_VEL + j] = vm - _skew_elem(ax, ay, az, i, j)
            vp = 0.0
            for k in range(3):
                vp += _skew_elem(ve, vn, vu, i, k) * (2.0 * Mp1[3 * k + j] + Mp2[3 * k + j])
            F[X_VEL + i, X_POS + j] = vp
    # gravity: up component of dg with latitude and height
    F[_VU, _LAT] += -_dgravity_dlat(sl, cl)
    F[_VU, _HGT] += -(gravity_sin_nb(sl, h + 0.5) - gravity_sin_nb(sl, h - 0.5))
    # position rows (dlat, dlon, dh)
    F[_LAT, _VN] = 1.0 / rmh
    F[_LAT, _HGT] = -vn / rmh**2
    F[_LON, _VE] = 1.0 / (rnh * cl)
    F[_LON, _LAT] = ve * tl / (rnh * cl)
    F[_LON, _HGT] = -ve / (rnh**2 * cl)
    F[_HGT, _VU] = 1.0
    # --- metric position error: D F D^-1 + dD/dt D^-1, D = diag of the dpos_n order ---
    _to_metric(F, lat, rmh, rnh, vn, vu, tl, cl)
    # --- sensor-error blocks, each as its registered coupling says ---
    n = F.shape[0]
    for b in range(blk_start.size):
        s0 = blk_start[b]
        if blk_kind[b] == COUPLE_GYRO or blk_kind[b] == COUPLE_ACCEL:
            row = X_ATT if blk_kind[b] == COUPLE_GYRO else X_VEL
            sign = -1.0 if blk_kind[b] == COUPLE_GYRO else 1.0
            for i in range(3):
                for j in range(3):
                    F[row + i, s0 + j] = sign * C_bn[i, j]
        for i in range(s0, block_end(blk_start, b, n)):
            F[i, i] = -blk_inv_tau[b]


@nb.njit(cache=True, error_model="numpy")
def block_end(blk_start, b, n):
    """One past the last state of sensor block ``b`` (blocks are contiguous up to ``n``)."""
    return blk_start[b + 1] if b + 1 < blk_start.size else n


@nb.njit(cache=True, error_model="numpy")
def _to_metric(F, lat, rmh, rnh, vn, vu, tl, cl):
    """Convert the position columns/rows from (dlat, dlon, dh) to ENU metres in place."""
    n = F.shape[0]
    # radian state r = (dlat, dlon, dh) -> metres m = (dE, dN, dU) = (D1 dlon, D0 dlat, dh)
    d_lat, d_lon = rmh, rnh * cl
    # new columns: F[:, m] = F[:, r] / D  (permuting lat/lon into N/E order)
    for i in range(n):
        c_lat, c_lon = F[i, _LAT], F[i, _LON]
        F[i, _E] = c_lon / d_lon
        F[i, _N] = c_lat / d_lat
    for j in range(n):
        r_lat, r_lon = F[_LAT, j], F[_LON, j]
        F[_E, j] = r_lon * d_lon
        F[_N, j] = r_lat * d_lat
    # dD/dt D^-1 terms (heights change the radii of the metric map)
    F[_E, _E] += vu / rnh - tl * vn / rmh
    F[_N, _N] += vu / rmh


@nb.njit(cache=True, error_model="numpy")
def _skew_elem(x, y, z, i, j):
    """Element (i, j) of [v x] for v = (x, y, z)."""
    if i == j:
        return 0.0
    if i == 0:
        return -z if j == 1 else y
    if i == 1:
        return z if j == 0 else -x
    return -y if j == 0 else x


@nb.njit(cache=True, error_model="numpy")
def _skew_into(F, r0, c0, x, y, z):
    F[r0, c0 + 1] += -z
    F[r0, c0 + 2] += y
    F[r0 + 1, c0] += z
    F[r0 + 1, c0 + 2] += -x
    F[r0 + 2, c0] += -y
    F[r0 + 2, c0 + 1] += x


@nb.njit(cache=True, error_model="numpy")
def discretize(F, q_diag, dt, Phi, Qd, work):
    """Second-order transition matrix and process noise over ``dt``.

    Parameters
    ----------
    F : (n, n) continuous system matrix.
    q_diag : (n,) continuous white-noise spectral densities (per state).
    dt : float
    Phi, Qd : (n, n) outputs.
    work : (n, n) scratch.
    """
    discretize_tail(F, q_diag, dt, Phi, Qd, work, diagonal_tail(F))


@nb.njit(cache=True, error_model="numpy")
def discretize_tail(F, q_diag, dt, Phi, Qd, work, d):
    """:func:`discretize` for an ``F`` whose rows from ``d`` on are diagonal; ``Phi`` then
    has the same tail (:func:`~fuzzynav.filters.kalman.propagate_tail`)."""
    n = F.shape[0]
    if sized.fixed(n, d):  # the 15-state model: a copy compiled with its sizes as constants
        sized.discretize_sized(F, q_diag, dt, Phi, Qd, work, sized.FIXED_N, sized.FIXED_D)
    else:
        sized.discretize_sized(F, q_diag, dt, Phi, Qd, work, n, d)


@nb.njit(cache=True, error_model="numpy")
def transition(F, dt, Phi, work):
    """Second-order transition matrix ``Phi = I + F dt + (F dt)^2 / 2`` (``work``: scratch)."""
    _transition(F, diagonal_tail(F), dt, Phi, work)


@nb.njit(cache=True, error_model="numpy")
def _transition(F, d, dt, Phi, work):
    """:func:`transition` for ``F`` with rows diagonal from ``d`` on."""
    n = F.shape[0]
    square_tail(F, d, work)  # work = F @ F
    h2 = 0.5 * dt * dt
    for i in range(n):
        for j in range(n):
            Phi[i, j] = F[i, j] * dt + work[i, j] * h2
        Phi[i, i] += 1.0
