"""``apso``: an EKF whose Q and R diagonals are scaled by tuned multipliers (paper 004).

Paper 004 tunes the process and measurement noise of a SINS/DVL Kalman filter with an
adaptive-inertia particle swarm (fitness: RMS position error against a reference).  The
multipliers it finds are constants, so the filter itself is an EKF with the constant
multipliers of :mod:`fuzzynav.filters.multipliers` (``q_att``, ``q_vel``, ``q_gyro_bias``,
``q_accel_bias``, ``r_all``, ``r_<channel>`` -- ``r_vel_b`` for the DVL), the same keys as
``ekf-tuned``.

Give them as filter options, or as the parameter file of a baseline study
(``studies/paper004_apso.toml``, ``fuzzynav study run``) whose ``filters.apso`` object holds
them: ``--filter apso@studies/paper004_apso.json``, ``--rules FILE`` or the option
``params``.  Without any the filter is the plain EKF.
"""
from __future__ import annotations

from pathlib import Path

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.classical import ConstantScale
from fuzzynav.filters.baselines import params_of
from fuzzynav.filters.multipliers import is_multiplier, r_scales, scaled_config
from fuzzynav.filters.named import FilterSetup, base_config, every_sensor, register_filter
from fuzzynav.filters.params_file import check_params

__all__ = ["apso_multipliers"]


def apso_multipliers(ctx) -> dict:
    """The multipliers of ``apso``: its file's ``filters.apso`` (option ``params`` or one rule
    file) updated by the multiplier options, every key and range checked."""
    opts = ctx.options
    given = opts.get("params") or opts.get("rules")
    files = [given] if isinstance(given, (str, Path)) else list(given or [])
    if len(files) > 1:
        raise InputFileError(files[1], "", "apso takes one result file")
    mult = params_of(ctx, "apso", files[0]) if files else {}
    own = {k: v for k, v in opts.items() if is_multiplier(k)}
    mult.update(check_params("apso", own, None, "options.") if own else {})
    return mult


@register_filter("apso", "EKF with Q/R multipliers tuned by paper 004's adaptive PSO "
                         "(a baseline study's parameter file as its rule file, e.g. "
                         "apso@studies/paper004_apso.json; none = the EKF)", takes_rules=True,
                 takes_params=True)
def _apso(ctx) -> FilterSetup:
    mult = apso_multipliers(ctx)
    cfg = scaled_config(base_config(ctx), mult)
    per_channel, default = r_scales(mult)
    if not per_channel and default == 1.0:
        return FilterSetup(cfg)
    return every_sensor(ctx, lambda: ConstantScale(per_channel, default), cfg)
