"""Tuned classical baselines: named filters whose parameters come from a baseline study.

A baseline study (``fuzzynav study run studies/paper000_baselines.toml``, see
:mod:`fuzzynav.tuning.baseline_config`) tunes each classical filter with the same budget and
training runs as a fuzzy study and writes the best parameters to a JSON file::

    {"format": "fuzzynav-baselines", "version": 1, "study": "...",
     "filters": {"ekf-tuned": {"q_att": 1.3, "q_vel": 0.8, "r_pos": 6.1, ...},
                 "sage-husa-tuned": {"b": 0.97, "floor": 0.2, "cap": 40.0}, ...}}

The filters here read it: ``ekf-tuned@FILE`` (or the option ``params``); without one, the
file :data:`DEFAULT_PARAMS` is looked up in ``./studies`` and then the checkout's
``studies/`` (see :func:`fuzzynav.filters.catalog.find_params_file`).

* ``ekf-tuned`` -- constant multipliers of the process-noise densities (``q_att`` on the
  ARW, ``q_vel`` on the VRW, ``q_gyro_bias`` / ``q_accel_bias`` on the bias random walks;
  variance factors) and of R (``r_all``, ``r_<channel>``; the one vocabulary of
  :mod:`fuzzynav.filters.multipliers`);
* ``sage-husa-tuned`` (``b``, ``floor``, ``cap``), ``vb-tuned`` (``rho``, ``iterations``),
  ``huber-tuned`` (``gamma``), ``strong-tracking-tuned`` (``rho``, ``beta``, ``lam_max``);
* ``strong-tracking`` -- Zhou's filter with its textbook constants (rho 0.95, beta 1, no
  cap; it diverges on the paper-000 runs, see ``docs/science.md``);
* ``als`` -- the EKF with the constant Q and R multipliers the autocovariance
  least-squares estimate gave on the training runs (same keys as ``ekf-tuned``).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.filters import measurements
from fuzzynav.filters.adaptation.classical import (ConstantScale, Huber, SageHusa,
                                                   VariationalBayes)
from fuzzynav.filters.adaptation.strong_tracking import StrongTracking
from fuzzynav.filters.catalog import find_params_file
from fuzzynav.filters.multipliers import Q_FIELDS, r_scales, scaled_config
from fuzzynav.filters.params_file import read_params_file
from fuzzynav.filters.named import FilterSetup, base_config, every_sensor, register_filter

#: the tuned-parameter file used when a filter is named without ``@FILE``
DEFAULT_PARAMS = "paper000_baselines.json"
__all__ = ["DEFAULT_PARAMS", "Q_FIELDS", "TUNED", "file_params", "find_params_file",
           "hqh_per_channel", "params_of", "read_params", "scaled_noise_setup"]


def read_params(path) -> dict:
    """The ``filters`` table of a tuned-parameter file found by :func:`find_params_file`,
    every key and range checked (:func:`fuzzynav.filters.params_file.read_params_file`)."""
    path = find_params_file(path)
    return {"path": Path(path), "filters": read_params_file(path)}


def file_params(path, name: str) -> dict:
    """The tuned parameters of filter ``name`` in the tuned-parameter file ``path``
    (:class:`~fuzzynav.errors.InputFileError` naming ``$.filters.<name>`` if it has none)."""
    doc = read_params(path)
    if name not in doc["filters"]:
        raise InputFileError(doc["path"], f"$.filters.{name}",
                             f"missing (this file tunes: {', '.join(doc['filters']) or 'none'}"
                             "); run the baseline study that tunes it")
    return dict(doc["filters"][name])


def params_of(ctx, name: str, default=DEFAULT_PARAMS) -> dict:
    """The tuned parameters of filter ``name`` (from ``params`` or the file ``default``)."""
    return file_params(ctx.options.get("params") or default, name)


def scaled_noise_setup(ctx, params: dict) -> FilterSetup:
    """The EKF with constant Q and R multipliers (:mod:`fuzzynav.filters.multipliers`)."""
    scales, default = r_scales(params)
    return every_sensor(ctx, lambda: ConstantScale(scales, default),
                        scaled_config(base_config(ctx), params))


def hqh_per_channel(cfg, data) -> dict:
    """``(H Q H^T)_ii`` per channel of a sensor: the white IMU noise over one epoch interval.

    Velocity rows see ``VRW^2 T``, position rows ``VRW^2 T^3 / 3`` (the velocity noise
    integrated), angle rows ``ARW^2 T``; ``T`` is the sensor's median epoch interval.
    """
    t = np.asarray(data.time_s, float)
    T = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    qv = (cfg.vrw_ug_psqrthz * units.UG) ** 2
    qa = (cfg.arw_dpsh * units.DPSH) ** 2
    out = {}
    for c in measurements.get(data.kind).channels:
        out[c] = qv * T**3 / 3.0 if c == "pos" else qv * T if c == "vel" else qa * T
    return out


def _strong_tracking(ctx, rho: float, beta: float, lam_max: float = math.inf) -> FilterSetup:
    cfg = base_config(ctx)
    return FilterSetup(cfg, {nm: StrongTracking(rho, beta, lam_max, hqh=hqh_per_channel(cfg, d))
                             for nm, d in ctx.sensors.items()})


#: tuned filter -> (description, setup from (context, parameters))
TUNED = {
    "ekf-tuned": ("EKF with constant Q and R multipliers tuned by a baseline study",
                  scaled_noise_setup),
    "sage-husa-tuned": ("Sage-Husa with b and its R bounds tuned by a baseline study",
                        lambda ctx, p: every_sensor(ctx, lambda: SageHusa(
                            p.get("b", 0.98), p.get("floor", 0.1), p.get("cap", math.inf)))),
    "vb-tuned": ("variational Bayes with rho and iterations tuned by a baseline study",
                 lambda ctx, p: every_sensor(ctx, lambda: VariationalBayes(
                     p.get("rho", 0.98), int(round(p.get("iterations", 3)))))),
    "huber-tuned": ("Huber with gamma tuned by a baseline study",
                    lambda ctx, p: every_sensor(ctx, lambda: Huber(p.get("gamma", 1.345)))),
    "strong-tracking-tuned": ("Zhou's strong tracking with rho and beta tuned by a "
                              "baseline study",
                              lambda ctx, p: _strong_tracking(ctx, p.get("rho", 0.95),
                                                              p.get("beta", 1.0),
                                                              p.get("lam_max", math.inf))),
    "als": ("EKF with constant Q and R from autocovariance least squares on training runs",
            scaled_noise_setup),
}


def _register_tuned(name: str, description: str, build) -> None:
    @register_filter(name, description + " (NAME@FILE or option params; default "
                     f"{DEFAULT_PARAMS})", takes_params=True)
    def _make(ctx):
        return build(ctx, params_of(ctx, name))


for _name, (_desc, _build) in TUNED.items():
    _register_tuned(_name, _desc, _build)


@register_filter("strong-tracking", "Zhou's strong tracking filter (fading factor with "
                                    "softening factor beta = 1, rho = 0.95)")
def _strong_default(ctx):
    return _strong_tracking(ctx, float(ctx.options.get("rho", 0.95)),
                            float(ctx.options.get("beta", 1.0)))
