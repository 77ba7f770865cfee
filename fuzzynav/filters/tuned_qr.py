"""``apso``: an EKF whose Q and R diagonals are scaled by tuned multipliers (paper 004).

Paper 004 tunes the process and measurement noise of a SINS/DVL Kalman filter with an
adaptive-inertia particle swarm (fitness: RMS position error against a reference).  The
multipliers it finds are constants, so the filter itself is an EKF with

* ``q_scale_att``, ``q_scale_vel``: factors on the angle / velocity random-walk *variance*
  densities (the attitude and velocity rows of Q);
* ``q_scale_gyro``, ``q_scale_accel``: factors on the bias random-walk variance densities
  (they change nothing when the nominal IMU has no bias random walk);
* ``r_scale``: factor on every measurement variance (all channels), or ``r_scale_<channel>``
  per channel (``r_scale_vel_b`` for the DVL).

Give them as filter options, or as an APSO result file given as the filter's rule file
(``--filter apso@studies/paper004_apso.json``, ``--rules FILE`` or the option ``apso_file``):
the parameter file of a baseline study (``studies/paper004_apso.toml``, ``fuzzynav study run``),
whose ``filters.apso`` object holds the same keys, or an older file with a ``multipliers``
object.  Without any the filter is the plain EKF.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.classical import ConstantScale
from fuzzynav.filters.params_file import APSO_Q_KEYS, check_params, read_params_file
from fuzzynav.filters.named import FilterSetup, config_from_imu, config_overrides, \
    register_filter

#: multiplier keys besides the per-channel ``r_scale_<channel>``
Q_KEYS = APSO_Q_KEYS


def read_multipliers(path) -> dict:
    """The ``multipliers`` object of an APSO result file (positive finite numbers)."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, "", f"cannot be read ({exc.__class__.__name__}: {exc})")
    except json.JSONDecodeError as exc:
        raise InputFileError(path, "", f"is not JSON ({exc.msg} at line {exc.lineno})")
    if isinstance(doc, dict) and "multipliers" not in doc and "filters" in doc:
        # a baseline study's parameter file (studies/paper004_apso.toml): its "apso" entry
        filters = read_params_file(path)
        if "apso" not in filters:
            raise InputFileError(path, "$.filters.apso", "missing (this file tunes: "
                                 f"{', '.join(filters) or 'none'})")
        return filters["apso"]
    mult = doc.get("multipliers") if isinstance(doc, dict) else None
    if not isinstance(mult, dict):
        raise InputFileError(path, "$.multipliers", "missing or not an object")
    return check_params("apso", mult, path, "$.multipliers.")


def check_multipliers(mult: dict, path=None, prefix="") -> dict:
    """Refuse unknown keys and factors outside the multiplier range (an empty set is the
    plain EKF: allowed for filter options, refused in files by the file readers)."""
    return check_params("apso", mult, path, prefix) if mult else {}


def scaled_config(base, mult: dict):
    """``base`` FilterConfig with the Q multipliers applied (square roots on the densities)."""
    def s(key):
        return math.sqrt(mult.get(key, 1.0))

    return base.with_(arw_dpsh=base.arw_dpsh * s("q_scale_att"),
                      vrw_ug_psqrthz=base.vrw_ug_psqrthz * s("q_scale_vel"),
                      gyro_rw_dph_psh=tuple(x * s("q_scale_gyro") for x in base.gyro_rw_dph_psh),
                      accel_rw_ug_psqrts=tuple(x * s("q_scale_accel")
                                               for x in base.accel_rw_ug_psqrts))


@register_filter("apso", "EKF with Q/R multipliers tuned by paper 004's adaptive PSO "
                         "(a baseline study's parameter file as its rule file, e.g. "
                         "apso@studies/paper004_apso.json; none = the EKF)", takes_rules=True)
def _apso(ctx) -> FilterSetup:
    from fuzzynav.filters.catalog import find_rule_file

    opts = dict(ctx.options)
    given = opts.get("apso_file") or opts.get("rules")
    files = [given] if isinstance(given, (str, Path)) else list(given or [])
    if len(files) > 1:
        raise InputFileError(files[1], "", "apso takes one result file")
    mult = read_multipliers(find_rule_file(files[0])) if files else {}
    mult.update(check_multipliers({k: v for k, v in opts.items()
                                   if k in Q_KEYS or str(k).startswith("r_scale")}))
    cfg = scaled_config(config_from_imu(ctx.imu_noise, **config_overrides(opts)), mult)
    per_channel = {k[len("r_scale_"):]: v for k, v in mult.items() if k.startswith("r_scale_")}
    default = mult.get("r_scale", 1.0)
    if not per_channel and default == 1.0:
        return FilterSetup(cfg)
    return FilterSetup(cfg, {nm: ConstantScale(per_channel, default) for nm in ctx.sensors})
