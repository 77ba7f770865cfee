"""Attitude mathematics: DCM, quaternion, Euler angles, rotation vectors.

Conventions (used everywhere in fuzzynav)
------------------------------------------
* Navigation frame n: ENU.  Body frame b: **RFU** — x right, y forward, z up (the frame of
  the source papers and of PSINS).  Real-data loaders rotate their sensors into RFU.
* ``C_bn`` is the direction-cosine matrix taking body vectors to navigation vectors,
  ``v_n = C_bn @ v_b``.
* Euler angles ``att = (pitch, roll, heading)`` [rad], yaw-pitch-roll (3-1-2) order::

      C_bn = R3(-heading) @ R1(pitch) @ R2(roll)

  with ``Rk(a)`` the active (right-hand) rotation by ``a`` about axis k.  Pitch is positive
  nose up, roll positive right wing down, **heading is the azimuth of the forward axis
  measured clockwise from north** (0 = north, pi/2 = east), wrapped to [0, 2 pi).
* Quaternions are scalar-first Hamilton ``q = [w, x, y, z]`` representing ``C_bn``:
  ``v_n = q * v_b * conj(q)``.
* The attitude error of a computed ``C_bn_calc`` against truth is the small rotation
  ``phi_n`` with ``C_bn_calc = (I - [phi_n x]) C_bn_true`` (the psi/phi-angle of the error
  model); see :func:`attitude_error`.

Functions work on single values or stacks (leading dimensions) unless noted.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["TWO_PI", "mod_pos", "wrap_pi", "wrap_2pi", "skew", "euler_to_dcm", "dcm_to_euler",
           "quat_multiply", "quat_conj", "quat_normalize", "quat_to_dcm", "dcm_to_quat",
           "rotvec_to_quat", "quat_to_rotvec", "rotvec_to_dcm", "dcm_to_rotvec",
           "euler_to_quat", "quat_to_euler", "attitude_error", "euler_error"]

TWO_PI = 2.0 * math.pi


@nb.njit(cache=True, error_model="numpy")
def mod_pos(a, m):
    """``a % m`` (``m > 0``) without the ``fmod`` when ``a`` already lies in ``(0, m)``.

    There the remainder is ``a`` itself, bit for bit, and that is the usual case of the
    angles folded here: the same numbers, a library call less.
    """
    if 0.0 < a < m:
        return a
    return a % m


@nb.vectorize(["float64(float64)"], cache=True)
def wrap_pi(angle_rad):
    """Wrap angles to [-pi, pi).  The one place angle wrapping is done.

    A numba ufunc: called from Python on a value or an array of any shape, and from numba
    kernels on a scalar.  Bit for bit ``(angle_rad + pi) % (2 pi) - pi``.
    """
    shifted = angle_rad + math.pi
    if shifted != shifted:  # NaN as numpy gives it, without the invalid-operation warning
        return shifted      # that the ordered comparison of mod_pos would raise
    return mod_pos(shifted, TWO_PI) - math.pi


def wrap_2pi(angle_rad):
    """Wrap angles to [0, 2 pi) (headings)."""
    return np.asarray(angle_rad) % TWO_PI


def skew(v):
    """Cross-product matrix ``[v x]`` of vectors, shape (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def euler_to_dcm(att_rad):
    """Euler angles ``(pitch, roll, heading)`` [rad] to ``C_bn``, shape (..., 3, 3)."""
    att = np.asarray(att_rad, dtype=float)
    sp, cp = np.sin(att[..., 0]), np.cos(att[..., 0])
    sr, cr = np.sin(att[..., 1]), np.cos(att[..., 1])
    sh, ch = np.sin(att[..., 2]), np.cos(att[..., 2])
    row0 = np.stack([ch * cr + sh * sp * sr, sh * cp, ch * sr - sh * sp * cr], -1)
    row1 = np.stack([-sh * cr + ch * sp * sr, ch * cp, -sh * sr - ch * sp * cr], -1)
    row2 = np.stack([-cp * sr, sp, cp * cr], -1)
    return np.stack([row0, row1, row2], -2)


def dcm_to_euler(C_bn):
    """``C_bn`` to Euler angles ``(pitch, roll, heading)`` [rad], heading in [0, 2 pi)."""
    C = np.asarray(C_bn, dtype=float)
    pitch = np.arcsin(np.clip(C[..., 2, 1], -1.0, 1.0))
    roll = np.arctan2(-C[..., 2, 0], C[..., 2, 2])
    heading = wrap_2pi(np.arctan2(C[..., 0, 1], C[..., 1, 1]))
    return np.stack([pitch, roll, heading], -1)


def quat_multiply(p, q):
    """Hamilton product ``p * q`` of scalar-first quaternions, shape (..., 4)."""
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack([pw * qw - px * qx - py * qy - pz * qz,
                     pw * qx + px * qw + py * qz - pz * qy,
                     pw * qy - px * qz + py * qw + pz * qx,
                     pw * qz + px * qy - py * qx + pz * qw], -1)


def quat_conj(q):
    """Conjugate (inverse of a unit quaternion)."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q):
    """Unit quaternion with non-negative scalar part."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_to_dcm(q):
    """Unit quaternion to DCM, shape (..., 3, 3)."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack([
        np.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
    ], -2)


def dcm_to_quat(C):
    """DCM to unit quaternion (Shepperd's method, numerically safe), shape (..., 4)."""
    C = np.asarray(C, dtype=float)
    tr = np.trace(C, axis1=-2, axis2=-1)
    cand = np.stack([tr, C[..., 0, 0], C[..., 1, 1], C[..., 2, 2]], -1)
    k = np.argmax(cand, axis=-1)
    q = np.empty(C.shape[:-2] + (4,))
    d = np.sqrt(np.maximum(1.0 + 2.0 * np.take_along_axis(cand, k[..., None], -1)[..., 0]
                           - tr, 0.0)) / 2.0
    # one branch per largest component keeps the divisor away from zero
    b = k == 0
    q[b] = np.stack([d[b], (C[b][:, 2, 1] - C[b][:, 1, 2]) / (4 * d[b]),
                     (C[b][:, 0, 2] - C[b][:, 2, 0]) / (4 * d[b]),
                     (C[b][:, 1, 0] - C[b][:, 0, 1]) / (4 * d[b])], -1)
    for i in range(3):
        b = k == i + 1
        j, m = (i + 1) % 3, (i + 2) % 3
        qi = np.empty((int(b.sum()), 4))
        qi[:, 0] = (C[b][:, m, j] - C[b][:, j, m]) / (4 * d[b])
        qi[:, 1 + i] = d[b]
        qi[:, 1 + j] = (C[b][:, j, i] + C[b][:, i, j]) / (4 * d[b])
        qi[:, 1 + m] = (C[b][:, m, i] + C[b][:, i, m]) / (4 * d[b])
        q[b] = qi
    return quat_normalize(q)


def rotvec_to_quat(rv):
    """Rotation vector [rad] to unit quaternion (series near zero), shape (..., 4)."""
    rv = np.asarray(rv, dtype=float)
    a2 = np.sum(rv * rv, -1)
    a = np.sqrt(a2)
    small = a2 < 1e-8
    # Taylor series keeps full precision for tiny rotations (per-sample increments)
    s = np.where(small, 0.5 - a2 / 48.0 + a2 * a2 / 3840.0,
                 np.sin(0.5 * a) / np.where(small, 1.0, a))
    c = np.where(small, 1.0 - a2 / 8.0 + a2 * a2 / 384.0, np.cos(0.5 * a))
    return np.concatenate([c[..., None], s[..., None] * rv], -1)


def quat_to_rotvec(q):
    """Unit quaternion to rotation vector [rad] (angle in [0, pi]), shape (..., 3)."""
    q = quat_normalize(q)
    v = q[..., 1:]
    sn = np.linalg.norm(v, axis=-1)
    ang = 2.0 * np.arctan2(sn, q[..., 0])
    scale = np.where(sn < 1e-12, 2.0 / np.maximum(q[..., 0], 1e-300),
                     ang / np.where(sn < 1e-12, 1.0, sn))
    return v * scale[..., None]


def rotvec_to_dcm(rv):
    """Rotation vector [rad] to DCM (Rodrigues)."""
    return quat_to_dcm(rotvec_to_quat(rv))


def dcm_to_rotvec(C):
    """DCM to rotation vector [rad]."""
    return quat_to_rotvec(dcm_to_quat(C))


def euler_to_quat(att_rad):
    """Euler angles ``(pitch, roll, heading)`` [rad] to the quaternion of ``C_bn``."""
    att = np.asarray(att_rad, dtype=float)
    z = np.zeros(att.shape[:-1])
    qh = rotvec_to_quat(np.stack([z, z, -att[..., 2]], -1))
    qp = rotvec_to_quat(np.stack([att[..., 0], z, z], -1))
    qr = rotvec_to_quat(np.stack([z, att[..., 1], z], -1))
    return quat_normalize(quat_multiply(quat_multiply(qh, qp), qr))


def quat_to_euler(q):
    """Quaternion of ``C_bn`` to Euler angles ``(pitch, roll, heading)`` [rad].

    Equal to the last bit to ``dcm_to_euler(quat_to_dcm(q))``: the five DCM entries the
    angles need, each by :func:`quat_to_dcm`'s expression (scoring a filter run converts
    every output epoch; the other four entries and the stacking are not worth their time).
    """
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    pitch = np.arcsin(np.clip(2 * (y * z + w * x), -1.0, 1.0))
    roll = np.arctan2(-(2 * (x * z - w * y)), w * w - x * x - y * y + z * z)
    heading = wrap_2pi(np.arctan2(2 * (x * y - w * z), w * w - x * x + y * y - z * z))
    return np.stack([pitch, roll, heading], -1)


def attitude_error(C_bn_calc, C_bn_true):
    """Attitude error ``phi_n`` [rad] with ``C_calc = (I - [phi x]) C_true`` (exact vee).

    Returns the rotation vector of ``C_true C_calc^T``, which equals ``phi_n`` to first
    order and is exact for any size of error.
    """
    C_calc = np.asarray(C_bn_calc, dtype=float)
    C_true = np.asarray(C_bn_true, dtype=float)
    return dcm_to_rotvec(C_true @ np.swapaxes(C_calc, -1, -2))


def euler_error(att_calc_rad, att_true_rad):
    """Differences of Euler angles ``calc - true`` [rad], each wrapped to [-pi, pi)."""
    return wrap_pi(np.asarray(att_calc_rad) - np.asarray(att_true_rad))
