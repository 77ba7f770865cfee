"""A straightforward numpy GNSS/INS error-state EKF — the speed and accuracy reference.

Written the way such a filter usually is: a Python loop over IMU samples, small numpy arrays,
the mechanization and the error-state covariance propagated **every sample** with
``Phi = I + F dt``, ``P = Phi P Phi^T + Q dt``, Joseph updates at GNSS epochs and closed-loop
feedback.  Same physics and state definition as :mod:`fuzzynav.filters` (phi-angle model,
position error in ENU metres, random-constant biases) but independent of the compiled loop:
the predict and update are the package's plain numpy ones (:mod:`fuzzynav.filters.reference`).
It is kept here as the benchmark's reference, not in the package.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.filters import reference
from fuzzynav.nav import earth

OMEGA = earth.OMEGA_IE


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _qmul(a, b):
    return np.array([a[0] * b[0] - a[1:] @ b[1:],
                     *(a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:]))])


def _rv2q(rv):
    a = np.linalg.norm(rv)
    if a < 1e-12:
        return np.array([1.0, *(0.5 * rv)])
    return np.array([np.cos(a / 2), *(np.sin(a / 2) / a * rv)])


def _q2dcm(q):
    w, x, y, z = q
    return np.array([[w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z]])


def _system_matrix(v, lat, h, C, f_n):
    """15x15 F: phi-angle model with the position error in ENU metres."""
    rm, rn = earth.radii(lat)
    rmh, rnh = rm + h, rn + h
    tl = np.tan(lat)
    wie = np.array([0.0, OMEGA * np.cos(lat), OMEGA * np.sin(lat)])
    wen = np.array([-v[1] / rmh, v[0] / rnh, v[0] * tl / rnh])
    # d(omega_en)/d(dv) and d(omega)/d(dpos) in metres (east, north, up)
    Mav = np.array([[0.0, -1.0 / rmh, 0.0], [1.0 / rnh, 0.0, 0.0], [tl / rnh, 0.0, 0.0]])
    dwie = np.array([[0.0, 0.0, 0.0], [0.0, -wie[2] / rmh, 0.0], [0.0, wie[1] / rmh, 0.0]])
    dwen = np.array([[0.0, 0.0, v[1] / rmh**2], [0.0, 0.0, -v[0] / rnh**2],
                     [0.0, v[0] / (rnh * np.cos(lat) ** 2 * rmh), -v[0] * tl / rnh**2]])
    F = np.zeros((15, 15))
    F[0:3, 0:3] = -_skew(wie + wen)
    F[0:3, 3:6] = Mav
    F[0:3, 6:9] = dwie + dwen
    F[0:3, 9:12] = -C
    F[3:6, 0:3] = _skew(f_n)
    F[3:6, 3:6] = _skew(v) @ Mav - _skew(2 * wie + wen)
    F[3:6, 6:9] = _skew(v) @ (2 * dwie + dwen)
    F[5, 8] += 2 * earth.gravity(lat, h) / (rm + h)  # free-air gradient, about 3.086e-6
    F[3:6, 12:15] = C
    F[6:9, 3:6] = np.eye(3)
    F[6, 6] += v[2] / rnh - tl * v[1] / rmh
    F[6, 7] += v[0] * tl / rmh
    F[6, 8] += -v[0] / rnh
    F[7, 7] += v[2] / rmh
    F[7, 8] += -v[1] / rmh
    return F


class NumpyEKF:
    """Per-sample numpy EKF; see the module docstring."""

    def __init__(self, lla, vel_n, q_bn, P0, q_diag):
        self.q, self.v, self.p = np.array(q_bn, float), np.array(vel_n, float), np.array(lla, float)
        self.P, self.qd = np.array(P0, float), np.array(q_diag, float)
        self.bg, self.ba = np.zeros(3), np.zeros(3)
        self.prev = None

    def step(self, dth, dv, dt):
        dth, dv = dth - self.bg * dt, dv - self.ba * dt
        pth, pdv, pv, pp = self.prev if self.prev is not None else (dth, dv, self.v, self.p)
        phi = dth + np.cross(pth, dth) / 12
        dvs = dv + 0.5 * np.cross(dth, dv) + np.cross(dth, np.cross(dth, dv)) / 6 \
            + (np.cross(pth, dv) + np.cross(pdv, dth)) / 12
        vm, pm = 1.5 * self.v - 0.5 * pv, 1.5 * self.p - 0.5 * pp
        rm, rn = earth.radii(pm[0])
        wie = np.array([0.0, OMEGA * np.cos(pm[0]), OMEGA * np.sin(pm[0])])
        wen = np.array([-vm[1] / (rm + pm[2]), vm[0] / (rn + pm[2]),
                        vm[0] * np.tan(pm[0]) / (rn + pm[2])])
        win = wie + wen
        C = _q2dcm(self.q)
        dvn = (np.eye(3) - 0.5 * _skew(win * dt)) @ (C @ dvs)
        g = np.array([0.0, 0.0, -earth.gravity(pm[0], pm[2])])
        v1 = self.v + dvn + (g - np.cross(2 * wie + wen, vm)) * dt
        h1 = self.p[2] + 0.5 * (self.v[2] + v1[2]) * dt
        hm = 0.5 * (self.p[2] + h1)
        lat1 = self.p[0] + 0.5 * (self.v[1] + v1[1]) * dt / (rm + hm)
        lon1 = self.p[1] + 0.5 * (self.v[0] + v1[0]) * dt / ((rn + hm) * np.cos(pm[0]))
        self.prev = (dth, dv, self.v.copy(), self.p.copy())
        self.q = _qmul(_rv2q(-win * dt), _qmul(self.q, _rv2q(phi)))
        self.q /= np.linalg.norm(self.q)
        self.v, self.p = v1, np.array([lat1, lon1, h1])
        F = _system_matrix(self.v, self.p[0], self.p[2], _q2dcm(self.q), dvn / dt)
        Phi = np.eye(15) + F * dt
        _, self.P = reference.predict(None, self.P, Phi, np.diag(self.qd) * dt)

    def update_gnss(self, row):
        lat, h = self.p[0], self.p[2]
        rm, rn = earth.radii(lat)
        z = np.r_[(self.p[1] - row[1]) * (rn + h) * np.cos(lat), (lat - row[0]) * (rm + h),
                  h - row[2], self.v - row[3:6]]
        H = np.zeros((6, 15))
        H[0:3, 6:9] = np.eye(3)
        H[3:6, 3:6] = np.eye(3)
        R = np.diag(np.square(row[6:12]))
        x, self.P = reference.update(np.zeros(15), self.P, z, H, R)
        self.q = _qmul(_rv2q(x[0:3]), self.q)
        self.v = self.v - x[3:6]
        d = np.array([x[7] / (rm + h), x[6] / ((rn + h) * np.cos(lat)), x[8]])
        self.p = self.p - d
        if self.prev is not None:
            pth, pdv, pv, pp = self.prev
            self.prev = (pth, pdv, pv - x[3:6], pp - d)
        self.bg, self.ba = self.bg + x[9:12], self.ba + x[12:15]


def run(imu, gnss, init, P0, q_diag, out_stride):
    """Run over all samples; returns (times, lla, vel_n, q_bn) every ``out_stride`` samples."""
    f = NumpyEKF(init.lla, init.vel_n, init.q_bn, P0, q_diag)
    t, gi = imu.time_s, 0
    rows = np.hstack([gnss.z, gnss.sigma])
    out = [(t[0], f.p.copy(), f.v.copy(), f.q.copy())]
    for k in range(imu.dtheta_b.shape[0]):
        f.step(imu.dtheta_b[k], imu.dv_b[k], t[k + 1] - t[k])
        while gi < gnss.time_s.size and gnss.time_s[gi] <= t[k + 1] + 1e-9:
            f.update_gnss(rows[gi])
            gi += 1
        if (k + 1) % out_stride == 0:
            out.append((t[k + 1], f.p.copy(), f.v.copy(), f.q.copy()))
    ts, p, v, q = zip(*out)
    return np.array(ts), np.array(p), np.array(v), np.array(q)
