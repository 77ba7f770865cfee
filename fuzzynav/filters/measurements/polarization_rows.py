"""Data rows of the polarization model, with what an imaging epoch's fit needs from the data.

A row is ``[z..., sigma...]`` (:func:`~fuzzynav.filters.measurements.default_rows`; the
columns of :mod:`fuzzynav.sim.sensors.polarization`).  An imaging sensor's rows go on with
:func:`extra_columns` columns for ``k`` views: the cosines and sines of the ``k`` AoPs,
the sun's azimuth ``atan2(sun_n, sun_e)``, and the sun's body direction and the number of
views from the AoPs alone (:func:`~fuzzynav.nav.polarization_imaging.sun_from_aops`).  They
depend on the measurements only, never on the filter, and a study runs the same recording
hundreds of times: they are computed once per measurement array and kept while it lives
(:func:`imaging_columns`), which spares every run ~14 trigonometric calls and a 3x3
eigenvector per epoch.  The same numba kernels compute them as the fit would, so the
numbers are the same as computing them at each epoch.

A kept entry is used only while its array holds the same bits as when it was computed: an
array changed in place is computed afresh, never read stale.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np
from numba import types

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.live_cache import LiveCache
from fuzzynav.nav.polarization_imaging import aop_trig, sun_from_aops, view_frames

__all__ = ["extra_columns", "extra_start", "fill_extra", "imaging_columns", "rows"]


def extra_columns(k: int) -> int:
    """Columns an imaging row carries after ``[z, sigma]`` for ``k`` views."""
    return 2 * k + 5


def extra_start(k: int) -> int:
    """First extra column: after the ``k + 3`` measurement and ``k + 3`` sigma columns."""
    return 2 * (k + 3)


@nb.njit(cache=True, error_model="numpy")
def fill_extra(aops, sun, frames, out):
    """Write an epoch's extra columns into ``out`` (``2k + 5``): ``[cos aop_1..k,
    sin aop_1..k, sun azimuth, s_x, s_y, s_z, n_used]`` (the kernel forms them itself for a
    row that lacks them)."""
    k = aops.size
    trig = aop_trig(aops)
    for i in range(2 * k):  # not a slice assignment: that compiles numba's shape-error
        out[i] = trig[i]  # message formatting, seconds on a cold cache
    out[2 * k] = math.atan2(sun[1], sun[0])
    sx, sy, sz, used = sun_from_aops(aops, trig, frames)
    out[2 * k + 1], out[2 * k + 2], out[2 * k + 3], out[2 * k + 4] = sx, sy, sz, used


# typed with generic (A) layouts, as the measurement kernel sees its rows: fill_extra and
# what it calls are then compiled once for both, not again for C arrays (cold start)
@njit_signature(types.float64[:, ::1](types.float64[:, :], types.float64[:], types.int64))
def _imaging_columns(z, frames, k):
    """:func:`fill_extra` of every row of ``z = [aop_1..k, sun_e, sun_n, sun_u]``."""
    out = np.empty((z.shape[0], 2 * k + 5))
    for e in range(z.shape[0]):
        fill_extra(z[e, :k], z[e, k:k + 3], frames, out[e])
    return out


#: z -> (copy of z's bits, views, columns); an entry leaves with z
_KEPT = LiveCache()


def imaging_columns(z: np.ndarray, views_b: np.ndarray) -> np.ndarray:
    """The extra columns of the rows of measurements ``z`` (M, k + 3) seen through views
    ``views_b`` (k, 3): computed once while ``z`` lives with the same bits."""
    kept = _KEPT.get(z)
    if kept is not None and np.array_equal(kept[1], views_b) \
            and np.array_equal(kept[0], z.view(np.int64)):
        return kept[2]
    k = views_b.shape[0]
    cols = _imaging_columns(np.ascontiguousarray(z, dtype=float),
                            view_frames(np.ascontiguousarray(views_b, dtype=float)), k)
    cols.setflags(write=False)
    if z.dtype == np.float64 and z.flags.c_contiguous:
        _KEPT.put(z, (z.view(np.int64).copy(), views_b.copy(), cols))
    return cols


def rows(data) -> np.ndarray:
    """Data rows of a polarization stream: ``[z, sigma]``, and for an imaging sensor the
    columns of :func:`imaging_columns` after them."""
    base = [data.z, data.sigma]
    if int(data.meta.get("sensor_type", 0)) != 0:
        views = np.asarray(data.meta.get("views_b", [[0.0, 0.0, 1.0]]), float).reshape(-1, 3)
        if data.z.ndim != 2 or data.z.shape[1] != views.shape[0] + 3:
            raise FuzzynavError(
                f"polarization data: z has shape {data.z.shape}, but meta views_b names "
                f"{views.shape[0]} views (z needs one AoP column per view and the sun's 3)")
        base.append(imaging_columns(data.z, views))
    return np.hstack(base).astype(float, copy=False)
