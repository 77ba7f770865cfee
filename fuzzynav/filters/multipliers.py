"""The one vocabulary of constant Q/R multipliers (``ekf-scaled``, ``ekf-tuned``, ``als``, ``apso``).

Every filter with constant noise multipliers reads the same keys, as filter options or from
a tuned-parameter file (:mod:`fuzzynav.filters.params_file`):

* ``q_att``, ``q_vel``: variance factors on the angle / velocity random-walk densities (the
  attitude and velocity rows of Q);
* ``q_gyro_bias``, ``q_accel_bias``: variance factors on the bias random walks (they change
  nothing when the nominal IMU has no bias random walk);
* ``r_all``: a factor on every measurement variance;
* ``r_<channel>``: a factor on one measurement channel's variance (``r_pos``, ``r_vel_b``);
  it replaces ``r_all`` on that channel.

Earlier versions used other names (``q_scale_att``, ``r_scale``, ``r_scale_<channel>``);
:func:`new_name` gives the new name of an old key, so that readers refuse it by name.
"""
from __future__ import annotations

import math

__all__ = ["Q_FIELDS", "R_ALL", "R_PREFIX", "OLD_NAMES", "new_name", "is_multiplier",
           "scaled_config", "r_scales"]

#: process-noise multipliers: key -> FilterConfig field (a noise density, scaled by sqrt)
Q_FIELDS = {"q_att": "arw_dpsh", "q_vel": "vrw_ug_psqrthz",
            "q_gyro_bias": "gyro_rw_dph_psh", "q_accel_bias": "accel_rw_ug_psqrts"}
#: the factor on every measurement channel
R_ALL = "r_all"
#: prefix of a per-channel measurement factor
R_PREFIX = "r_"
#: old keys (paper 004's ``apso`` and ``ekf-scaled``) -> their name now
OLD_NAMES = {"q_scale_att": "q_att", "q_scale_vel": "q_vel", "q_scale_gyro": "q_gyro_bias",
             "q_scale_accel": "q_accel_bias", "r_scale": R_ALL}
_OLD_R_PREFIX = "r_scale_"


def new_name(key) -> str | None:
    """The current name of an old multiplier key, or None if ``key`` is not an old one."""
    key = str(key)
    if key in OLD_NAMES:
        return OLD_NAMES[key]
    if key.startswith(_OLD_R_PREFIX):
        return R_PREFIX + key[len(_OLD_R_PREFIX):]
    return None


def is_multiplier(key) -> bool:
    """Whether ``key`` is a multiplier key of the vocabulary (or an old name of one)."""
    key = str(key)
    return key in Q_FIELDS or key.startswith(R_PREFIX) or new_name(key) is not None


def scaled_config(cfg, mult: dict):
    """``cfg`` (a FilterConfig) with the Q multipliers of ``mult`` applied.

    The configuration holds noise densities (sigmas): a variance factor ``q`` scales them
    by ``sqrt(q)``; fields whose key is absent are left as they are.
    """
    changes = {}
    for key, fld in Q_FIELDS.items():
        if key in mult:
            val = getattr(cfg, fld)
            s = math.sqrt(float(mult[key]))
            changes[fld] = tuple(v * s for v in val) if isinstance(val, tuple) else val * s
    return cfg.with_(**changes) if changes else cfg


def r_scales(mult: dict) -> tuple[dict, float]:
    """``(factor per channel, factor of the other channels)`` of the R multipliers."""
    per_channel = {k[len(R_PREFIX):]: float(v) for k, v in mult.items()
                   if k.startswith(R_PREFIX) and k != R_ALL}
    return per_channel, float(mult.get(R_ALL, 1.0))
