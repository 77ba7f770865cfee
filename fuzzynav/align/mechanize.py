"""Open-loop strapdown at a fixed place (numba): attitude and velocity at filter epochs.

At a known, fixed position only attitude and velocity are integrated; the navigation frame
turns with the earth (``w_ie^n``), the transport rate is zero.  Per IMU increment:
``q_bn <- q(-w_ie^n h) q_bn q(dtheta)`` and
``v <- v + C_bn (dv + a x dv / 2) + (g^n - 2 w_ie^n x v) h`` with
``a = dtheta - C_nb w_ie^n h`` the body's turn relative to the navigation frame (a
first-order rotation correction; with ``dtheta`` alone a body at rest would see a
spurious ``w_ie x f / 2`` acceleration).  Nothing is fed back: the alignment filter estimates
the errors of this solution (paper 002's open-loop form).
"""
from __future__ import annotations

import numba as nb
import numpy as np

from fuzzynav.nav import attitude, earth
from fuzzynav.nav.strapdown import quat_mul, rv2q

__all__ = ["Mechanizer", "mechanize"]


@nb.njit(cache=True)
def _rotate(q0, q1, q2, q3, x, y, z):
    """``C(q) v`` for a unit quaternion (scalars in, 3-tuple out)."""
    t0 = 2.0 * (q2 * z - q3 * y)
    t1 = 2.0 * (q3 * x - q1 * z)
    t2 = 2.0 * (q1 * y - q2 * x)
    return (x + q0 * t0 + q2 * t2 - q3 * t1,
            y + q0 * t1 + q3 * t0 - q1 * t2,
            z + q0 * t2 + q1 * t1 - q2 * t0)


@nb.njit(cache=True)
def _integrate(dtheta, dv, h, q_init, v_init, w_ie, g_up, step, out_q, out_v, out_f):
    q = q_init.copy()
    v = v_init.copy()
    fsum = np.zeros(3)
    for k in range(dtheta.shape[0]):
        c0, c1, c2 = dtheta[k, 0], dtheta[k, 1], dtheta[k, 2]
        d0, d1, d2 = dv[k, 0], dv[k, 1], dv[k, 2]
        # rotation of the body relative to the navigation frame over the increment
        w = _rotate(q[0], -q[1], -q[2], -q[3], w_ie[0] * h[k], w_ie[1] * h[k], w_ie[2] * h[k])
        a0, a1, a2 = c0 - w[0], c1 - w[1], c2 - w[2]
        r = _rotate(q[0], q[1], q[2], q[3], d0 + 0.5 * (a1 * d2 - a2 * d1),
                    d1 + 0.5 * (a2 * d0 - a0 * d2), d2 + 0.5 * (a0 * d1 - a1 * d0))
        cor0 = 2.0 * (w_ie[1] * v[2] - w_ie[2] * v[1])
        cor1 = 2.0 * (w_ie[2] * v[0] - w_ie[0] * v[2])
        cor2 = 2.0 * (w_ie[0] * v[1] - w_ie[1] * v[0])
        v[0] += r[0] - cor0 * h[k]
        v[1] += r[1] - cor1 * h[k]
        v[2] += r[2] + (-g_up - cor2) * h[k]
        for j in range(3):
            fsum[j] += r[j]
        a = rv2q(c0, c1, c2)
        b = quat_mul(q[0], q[1], q[2], q[3], a[0], a[1], a[2], a[3])
        e = rv2q(-w_ie[0] * h[k], -w_ie[1] * h[k], -w_ie[2] * h[k])
        b = quat_mul(e[0], e[1], e[2], e[3], b[0], b[1], b[2], b[3])
        s = 1.0 / np.sqrt(b[0] ** 2 + b[1] ** 2 + b[2] ** 2 + b[3] ** 2)
        for j in range(4):
            q[j] = b[j] * s
        if (k + 1) % step == 0:
            m = (k + 1) // step
            out_q[m] = q
            out_v[m] = v
            out_f[m] = fsum
            fsum[:] = 0.0


class Mechanizer:
    """The open-loop solution made chunk by chunk: attitude, velocity and mean specific
    force at every ``step``-th IMU sample, each chunk continuing from the last one's state
    (:func:`mechanize` is the one-chunk case).

    Every chunk but the last must hold a whole number of epochs (``step`` samples), so that
    an epoch's interval and its specific-force sum never straddle two chunks: the epochs
    are then the whole run's to the last bit.  Samples after the last whole epoch are left
    out, as one run over all of them leaves them.

    Parameters
    ----------
    C_bn0 : ndarray (3, 3)
        Initial attitude (from coarse alignment).
    lat_rad, h_m : float
        The fixed place.
    step : int
        IMU samples per filter epoch.
    vel0 : array_like, optional
        Initial velocity [m/s] (default zero).
    """

    def __init__(self, C_bn0, lat_rad, h_m, step, vel0=None):
        self.step = int(step)
        self.w_ie, self.g = earth.omega_ie_n(lat_rad), float(earth.gravity(lat_rad, h_m))
        self.q = [attitude.dcm_to_quat(np.asarray(C_bn0, dtype=float))[None]]
        self.v = [(np.zeros(3) if vel0 is None else np.asarray(vel0, dtype=float))[None]]
        self.f = []
        self.done = False   # a chunk that was not a whole number of epochs came (the last)

    def feed(self, imu) -> None:
        """The next chunk of increments (``time_s`` starting at the last chunk's end)."""
        if self.done:
            raise ValueError("Mechanizer: a chunk after one that was not a whole number of "
                             "epochs")
        n_ep = imu.dtheta_b.shape[0] // self.step
        k_end = n_ep * self.step
        self.done = k_end != imu.dtheta_b.shape[0]
        h = np.diff(imu.time_s)[:k_end]
        out_q, out_v, out_f = np.zeros((n_ep + 1, 4)), np.zeros((n_ep + 1, 3)), \
            np.zeros((n_ep + 1, 3))
        out_q[0], out_v[0] = self.q[-1][-1], self.v[-1][-1]
        _integrate(np.ascontiguousarray(imu.dtheta_b[:k_end]),
                   np.ascontiguousarray(imu.dv_b[:k_end]), h, out_q[0].copy(),
                   out_v[0].copy(), self.w_ie, self.g, self.step, out_q, out_v, out_f)
        T = h.reshape(n_ep, self.step).sum(1)
        self.q.append(out_q[1:])
        self.v.append(out_v[1:])
        self.f.append(out_f[1:] / T[:, None])

    def result(self):
        """``(C_bn, vel_n, f_n)`` at the epochs so far, as :func:`mechanize` returns them."""
        f = np.concatenate(self.f) if self.f else np.zeros((0, 3))
        f0 = f[:1] if f.shape[0] else np.zeros((1, 3))       # row 0 copies row 1
        return (attitude.quat_to_dcm(np.concatenate(self.q)), np.concatenate(self.v),
                np.concatenate([f0, f]))


def mechanize(imu, C_bn0, lat_rad, h_m, step, vel0=None):
    """Attitude, velocity and mean specific force at every ``step``-th IMU sample.

    Parameters
    ----------
    imu : ImuData
        Increments (``time_s``, ``dtheta_b``, ``dv_b``).
    C_bn0, lat_rad, h_m, step, vel0
        As :class:`Mechanizer` (the start, the place, the epoch length in samples).

    Returns
    -------
    C_bn : ndarray (M+1, 3, 3)
        Attitude at the epochs (epoch 0 is the start).
    vel_n : ndarray (M+1, 3)
        Velocity [m/s].
    f_n : ndarray (M+1, 3)
        Mean specific force over the interval ending at each epoch [m/s^2] (row 0 copies
        row 1).
    """
    m = Mechanizer(C_bn0, lat_rad, h_m, step, vel0)
    m.feed(imu)
    return m.result()
