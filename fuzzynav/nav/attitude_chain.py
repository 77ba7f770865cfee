"""A body attitude carried through a sequence of rotation increments: the cumulative
Hamilton product ``q[k] = q[k-1] * dq[k]``.

Numpy has no cumulative quaternion product, so the chain is a loop; compiled, it takes
about 10 ns a sample where the same loop in Python took about 3 us (the A-KIT loader's
gyro track chains every IMU sample of a recording, twice or three times a load).  The
products are written out in the order of :func:`fuzzynav.nav.attitude.quat_multiply`'s
components.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["chain_into", "chain"]


@nb.njit(cache=True, error_model="numpy")
def chain_into(q_prev, dq, out) -> None:
    """``out[k] = out[k-1] * dq[k]`` for each row of ``dq`` (unit quaternions, scalar
    first, (K, 4)), ``out[-1]`` being ``q_prev`` (4,)."""
    w, x, y, z = q_prev[0], q_prev[1], q_prev[2], q_prev[3]
    for k in range(dq.shape[0]):
        a, b, c, d = dq[k, 0], dq[k, 1], dq[k, 2], dq[k, 3]
        w, x, y, z = (w * a - x * b - y * c - z * d, w * b + x * a + y * d - z * c,
                      w * c - x * d + y * a + z * b, w * d + x * c - y * b + z * a)
        out[k, 0] = w
        out[k, 1] = x
        out[k, 2] = y
        out[k, 3] = z


def chain(q_prev, dq) -> np.ndarray:
    """The attitudes after ``q_prev`` (4,) carried through each increment of ``dq``
    (K, 4): an array (K, 4) (:func:`chain_into`)."""
    dq = np.ascontiguousarray(dq, dtype=float)
    out = np.empty((dq.shape[0], 4))
    chain_into(np.ascontiguousarray(q_prev, dtype=float), dq, out)
    return out
