"""The built-in named filters besides ``ekf``: fuzzy and classical adaptive filters.

Fuzzy filters take rule files (``--rules FILE``, repeatable).  A rule file's ``binding``
names the statistics and measurement channels it reads (``pos``, ``vel``, ``heading``, ...);
it is bound to every sensor of the run whose measurement model has those channels, or to
the sensor named by ``binding.sensor`` (a sensor name or kind).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fuzzynav.errors import DataMissingError, FuzzynavError, InputFileError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation.classical import (ConstantScale, FadingMemory, Huber, SageHusa,
                                                   VariationalBayes)
from fuzzynav.filters.adaptation.binding import BANK_CONTROLLERS, Binding
from fuzzynav.filters.multipliers import Q_FIELDS, is_multiplier, r_scales
from fuzzynav.filters.named import FilterContext, FilterSetup, base_config, every_sensor, \
    register_alias, register_filter

__all__ = ["PAPER000_RULES", "rules_dirs", "params_dirs", "find_file", "find_rule_file",
           "find_params_file", "bind_rule_files", "bind_systems"]

#: the paper's two controllers, used by ``fuzzy`` (alias ``fakf``) without ``--rules``
PAPER000_RULES = ("paper000_gps_sins.json", "paper000_attitude.json")


def rules_dirs() -> list[Path]:
    """Where rule files named without a directory are looked up, in order.

    ``FUZZYNAV_RULES``, ``./rules``, the checkout's ``rules/`` (source or editable install),
    then the copy a wheel ships in ``fuzzynav/rules`` (``setup.py`` puts it there).
    """
    dirs = [Path(p) for p in os.environ.get("FUZZYNAV_RULES", "").split(os.pathsep) if p]
    package = Path(__file__).resolve().parents[1]
    dirs += [Path.cwd() / "rules", package.parent / "rules", package / "rules"]
    return dirs


def params_dirs() -> list[Path]:
    """Where tuned-parameter files named without a directory are looked up, in order:
    ``./studies``, then the checkout's ``studies/`` (where the baseline studies write them)."""
    return [Path.cwd() / "studies", Path(__file__).resolve().parents[2] / "studies"]


def find_file(name, dirs, what: str, not_found: str) -> Path:
    """The one file finder: ``name`` as a path, or a bare file name looked up in ``dirs``.

    A directory or a special file (``/dev/null``, a FIFO: reading it would give nothing or
    hang) is refused; ``not_found`` ends the error of a file found nowhere.
    """
    p = Path(name)
    if p.is_file():
        return p
    if p.is_dir():
        raise InputFileError(p, "", f"is a directory, not a {what}")
    if p.exists():
        raise InputFileError(p, "", f"not a regular file (a {what} is a .json or .fis file)")
    if p.parent == Path("."):
        for d in dirs:
            if (d / p.name).is_file():
                return d / p.name
    raise DataMissingError(f"{name}: {what} not found ({not_found})")


def find_rule_file(name) -> Path:
    """A rule file by path, or by file name in :func:`rules_dirs`."""
    dirs = rules_dirs()
    return find_file(name, dirs, "rule file",
                     f"looked in: {', '.join(str(d) for d in dirs)}")


def find_params_file(name) -> Path:
    """A tuned-parameter file by path, or by file name in :func:`params_dirs`."""
    if not str(name).strip():
        raise InputFileError(None, "params", "names no file (NAME@ with nothing after the @)")
    return find_file(name, params_dirs(), "tuned-parameter file",
                     "run the baseline study that writes it, e.g. fuzzynav study run "
                     "studies/paper000_baselines.toml")


def bind_rule_files(paths, sensors: dict, required: bool = True) -> dict:
    """Adaptation policies from rule files, keyed by the sensor they bind to."""
    from fuzzynav.fuzzy import load_fis

    items = []
    for path in paths:
        path = find_rule_file(path)
        items.append((load_fis(path), str(path)))
    return bind_systems(items, sensors, required)


def bind_systems(items, sensors: dict, required: bool = True) -> dict:
    """Bind ``(fuzzy system, source)`` pairs to the run's sensors by their binding.

    A system binds to the sensor named (or of the kind named) by ``binding.sensor``, else
    to every sensor whose measurement model has all the channels its inputs read.
    """
    out = {}
    for fis, source in items:
        binding = Binding.of(fis, source)
        if binding.adapter in BANK_CONTROLLERS:
            raise FuzzynavError(f"{source}: {binding.adapter!r} controls a filter bank, not a "
                                "sensor: give it to a bank that takes one (federated-fuzzy-beta)")
        policy = adaptation.get(binding.adapter)(fis, source, binding)
        target = binding.sensor
        chans = set(binding.channels)
        if target:
            matched = [nm for nm, d in sensors.items() if target in (nm, d.kind)]
            for nm in matched:  # the named sensor must have the channels read
                binding.check_channels(measurements.get(sensors[nm].kind), source)
        else:
            matched = [nm for nm, d in sensors.items()
                       if chans and chans <= set(measurements.get(d.kind).channels)]
        if not matched:
            if required:
                raise FuzzynavError(
                    f"{source}: binding reads channels {sorted(chans) or ['all']}"
                    f"{' of sensor ' + repr(target) if target else ''}; no sensor of this run "
                    f"provides them (sensors: {', '.join(sorted(sensors)) or 'none'})")
            continue
        for nm in matched:
            if nm in out:
                raise FuzzynavError(f"{source}: sensor {nm!r} is already bound to "
                                    f"{out[nm].source}; give one rule set per sensor")
            out[nm] = policy
    return out


@register_filter("fuzzy", "fuzzy adaptive KF: each rule file (--rules FILE, repeatable) "
                          "binds the adapter it names; default: paper 000's two controllers",
                 takes_rules=True)
def _fuzzy(ctx: FilterContext) -> FilterSetup:
    given = ctx.options.get("rules")
    if given:
        adapters = bind_rule_files([given] if isinstance(given, (str, Path)) else given,
                                   ctx.sensors, required=True)
    else:
        adapters = bind_rule_files(PAPER000_RULES, ctx.sensors, required=False)
        if not adapters:
            raise FuzzynavError("fuzzy: none of the paper-000 rule files fits this run's "
                                "sensors")
    return FilterSetup(base_config(ctx), adapters)


# paper 000's name for it (FAKF: fuzzy adaptive Kalman filter), kept for scripts and studies
register_alias("fakf", "fuzzy")


@register_filter("sage-husa", "Sage-Husa adaptive R (b = 0.98)")
def _sage_husa(ctx):
    return every_sensor(ctx, lambda: SageHusa(ctx.options.get("b", 0.98)))


@register_filter("huber", "Huber M-estimation update (gamma = 1.345)")
def _huber(ctx):
    return every_sensor(ctx, lambda: Huber(ctx.options.get("gamma", 1.345)))


@register_filter("fading-memory", "strong-tracking fading memory (rho = 0.95, beta = 4, "
                                  "lambda <= 3)")
def _fading(ctx):
    # beta and the cap: with beta = 2 or lambda up to 10 it diverged on paper000 with a
    # compass (heading HPH << R makes the ratio noisy); these defaults were stable there
    return every_sensor(ctx, lambda: FadingMemory(ctx.options.get("rho", 0.95),
                                                   ctx.options.get("beta", 4.0),
                                                   ctx.options.get("lam_max", 3.0)))


@register_filter("vb", "variational-Bayes adaptive R (Sarkka & Nummenmaa, rho = 0.98)")
def _vb(ctx):
    return every_sensor(ctx, lambda: VariationalBayes(ctx.options.get("rho", 0.98)))


@register_filter("ekf-scaled", "EKF with constant R multipliers per channel "
                               "(options r_all / r_<channel>; a tuned baseline)")
def _ekf_scaled(ctx):
    from fuzzynav.filters.params_file import check_params

    mult = {k: v for k, v in ctx.options.items() if is_multiplier(k)}
    q = sorted(k for k in mult if k in Q_FIELDS)
    if q:
        raise FuzzynavError(f"ekf-scaled: options {', '.join(q)} scale Q; ekf-scaled scales "
                            "R only (ekf-tuned takes both)")
    mult = check_params("ekf-scaled", mult, None, "options.") if mult else {}
    scales, default = r_scales(mult)
    return every_sensor(ctx, lambda: ConstantScale(scales, default))


@register_filter("ekf-true", "EKF told the true (simulated) noise of every measurement epoch")
def _ekf_true(ctx):
    sensors = {}
    for nm, d in ctx.sensors.items():
        true = d.meta.get("true_sigma")
        if true is None:
            raise FuzzynavError(f"ekf-true: sensor {nm!r} carries no true noise "
                                "(only simulated sensors with meta['true_sigma'] do)")
        sensors[nm] = np.asarray(true, float)
    return FilterSetup(base_config(ctx), sigma_override=sensors)
