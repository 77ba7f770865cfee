"""Degraded copies of GNSS fixes for the validation protocol on real data.

The usual protocol scores a filter fed with a degraded copy of RTK fixes against the
untouched ones: white noise of 1-3 m added to the positions, and simulated outages such as
60 s every 180 s (the KF-GINS evaluation).  Each helper returns a new
:class:`~fuzzynav.sim.sensors.SensorData` and never changes its input; the applied noise is
kept in ``meta`` as truth.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.nav import earth
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.sensors.gnss import in_windows, outage_windows

__all__ = ["add_white_noise", "with_outages"]


#: meta entries that are constants of the sensor, never per-epoch arrays
_CONSTANT_META = ("lever_arm_b", "outage_windows", "rate_hz")


def _per_epoch(key, value, m) -> bool:
    return (key not in _CONSTANT_META and isinstance(value, np.ndarray)
            and value.ndim >= 1 and value.shape[0] == m)


def add_white_noise(fixes: SensorData, sigma_pos_m, rng, sigma_vel_mps=0.0,
                    claim: str = "inflate") -> SensorData:
    """Fixes with white Gaussian noise added per ENU axis.

    Parameters
    ----------
    fixes : SensorData
        Kind ``gnss`` (columns lat, lon, h, vel_e, vel_n, vel_u).
    sigma_pos_m, sigma_vel_mps : float or array_like of 3
        1-sigma of the added noise per ENU axis [m], [m/s].
    rng : numpy.random.Generator
    claim : {"inflate", "keep", "replace"}
        What the copy claims as sigma: ``sqrt(old^2 + added^2)`` (default), the old value,
        or the added noise alone.

    Returns
    -------
    SensorData
        ``meta`` gains ``added_pos_enu_m`` and ``added_vel_enu_mps``.
    """
    if claim not in ("inflate", "keep", "replace"):
        raise ValueError(f"claim must be 'inflate', 'keep' or 'replace', got {claim!r}")
    m = fixes.time_s.size
    sp = np.broadcast_to(np.asarray(sigma_pos_m, dtype=float), (3,))
    sv = np.broadcast_to(np.asarray(sigma_vel_mps, dtype=float), (3,))
    g_pos, g_vel = rng.spawn(2)
    n_pos = sp * g_pos.standard_normal((m, 3))
    n_vel = sv * g_vel.standard_normal((m, 3))
    z = fixes.z.copy()
    dlat, dlon, dh = earth.enu_to_delta_lla(n_pos, z[:, 0], z[:, 2])
    z[:, 0] += dlat
    z[:, 1] += dlon
    z[:, 2] += dh
    z[:, 3:] += n_vel
    added = np.concatenate([sp, sv])
    if claim == "inflate":
        sigma = np.hypot(fixes.sigma, added)
    elif claim == "replace":
        sigma = np.broadcast_to(added, fixes.sigma.shape).copy()
    else:
        sigma = fixes.sigma.copy()
    meta = dict(fixes.meta, added_pos_enu_m=n_pos, added_vel_enu_mps=n_vel)
    return SensorData(kind=fixes.kind, time_s=fixes.time_s.copy(), z=z, sigma=sigma, meta=meta)


def with_outages(fixes: SensorData, period_s=180.0, duration_s=60.0, first_s=None,
                 windows=()) -> SensorData:
    """Fixes with the epochs inside outage windows removed.

    Parameters
    ----------
    period_s, duration_s : float
        Periodic outages: ``duration_s`` without fixes every ``period_s``.
    first_s : float, optional
        Start of the first outage [s on the data's clock]; default: one period after the
        first fix.
    windows : sequence of (start_s, end_s)
        Further explicit outages.

    Returns
    -------
    SensorData
        ``meta`` gains ``outage_windows`` (K, 2); per-epoch meta arrays are cut alike.
    """
    t = fixes.time_s
    t0 = float(t[0]) if t.size else 0.0
    first = t0 + period_s if first_s is None else first_s
    w = outage_windows(float(t[-1]) if t.size else 0.0, windows, period_s, duration_s, first)
    keep = ~in_windows(t, w)
    meta = {k: (v[keep] if _per_epoch(k, v, t.size) else v) for k, v in fixes.meta.items()}
    meta["outage_windows"] = w
    return SensorData(kind=fixes.kind, time_s=t[keep], z=fixes.z[keep],
                      sigma=fixes.sigma[keep], meta=meta)
