"""``align-kf-tuned``: paper 002's alignment KF with constant, tuned noise multipliers.

The classical counterpart of the tuned fuzzy alignment filter: the same 10-state filter
(``align-kf``) with ``R = r_all R0`` and the velocity and attitude rows of Q0 scaled by
``q_vel`` and ``q_att`` (variance factors; the bias rows of Q0 are zero, so there is nothing
to scale there).  The constants come from a tuned-parameter file (``fuzzynav-baselines``,
:mod:`fuzzynav.filters.params_file`, key ``filters.align-kf-tuned``) written by an alignment
study with ``filter = "align-kf-tuned"`` (``studies/align/paper002_baselines.toml``): the
filter is named ``align-kf-tuned@FILE``, or ``align-kf-tuned`` for :data:`DEFAULT_PARAMS`.
With every multiplier 1 it is ``align-kf`` bit for bit.
"""
from __future__ import annotations

import dataclasses
import math

from fuzzynav.align.model import AlignNoise

__all__ = ["NAME", "DEFAULT_PARAMS", "SPACE", "default_params_path", "scaled_noise",
           "tuned_params"]

#: the tuned classical alignment filter
NAME = "align-kf-tuned"
#: its parameter file when named without ``@FILE`` (in the checkout's ``studies/align/``)
DEFAULT_PARAMS = "paper002_baselines.json"
#: what an alignment study searches for it: key -> (low, high, log scale), the bounds of the
#: navigation baselines' Q and R multipliers (:mod:`fuzzynav.tuning.baseline_config`)
SPACE = {"r_all": (0.1, 100.0, True), "q_vel": (0.1, 10.0, True), "q_att": (0.1, 10.0, True)}


def default_params_path():
    """``studies/align/`` :data:`DEFAULT_PARAMS` of the checkout."""
    from fuzzynav.filters.catalog import params_dirs

    return params_dirs()[-1] / "align" / DEFAULT_PARAMS


def tuned_params(path=None) -> dict:
    """The multipliers of ``align-kf-tuned`` in the tuned-parameter file ``path`` (default
    :func:`default_params_path`), checked; errors name the file and the JSON path."""
    from fuzzynav.filters.baselines import file_params

    return file_params(path or default_params_path(), NAME)


def scaled_noise(noise: AlignNoise, params: dict) -> AlignNoise:
    """``noise`` with its R0 and the velocity and attitude rows of Q0 scaled by the variance
    factors ``params`` (``r_all``, ``q_vel``, ``q_att``; a missing key is 1).  The sigmas
    are scaled by the square roots, so a factor of 1 leaves every number as it was."""
    from fuzzynav.filters.params_file import check_params

    p = check_params(NAME, dict(params), None, "params.")
    return dataclasses.replace(
        noise, meas_sigma_mps=noise.meas_sigma_mps * math.sqrt(p.get("r_all", 1.0)),
        accel_noise_mps2_psqrts=noise.accel_noise_mps2_psqrts * math.sqrt(p.get("q_vel", 1.0)),
        gyro_noise_rps_psqrts=noise.gyro_noise_rps_psqrts * math.sqrt(p.get("q_att", 1.0)))
