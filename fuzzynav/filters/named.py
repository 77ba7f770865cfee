"""Filters selectable by name (``--filter ekf``): a configuration plus adaptation policies.

A named filter is a function of a :class:`FilterContext` (the nominal IMU noise, the sensor
streams and user options such as ``rules``) returning a :class:`FilterSetup`.  Register one
with :func:`register_filter`; the CLI, the experiment runner and studies look them up here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from fuzzynav import units
from fuzzynav.errors import FuzzynavError, brief
from fuzzynav.registry import Registry
from fuzzynav.filters.config import FilterConfig

__all__ = ["FilterContext", "FilterSetup", "select_sensors", "NamedFilter", "FILTERS",
           "register_filter", "register_alias", "parse_filter_spec", "get_filter", "list_filters",
           "config_from_imu", "markov_config", "config_overrides", "base_config", "every_sensor"]


@dataclass(frozen=True)
class FilterContext:
    """What a named filter may look at to configure itself.

    Attributes
    ----------
    imu_noise : object or None
        Nominal IMU noise in SI (:class:`fuzzynav.sim.imu.ImuNoise`); None = defaults.
    sensors : dict
        Sensor name -> SensorData of the run.
    options : dict
        User options (e.g. ``rules``: a rule file or list of them, ``init_att_sigma_deg``).
    """

    imu_noise: object = None
    sensors: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)


@dataclass(frozen=True)
class FilterSetup:
    """Everything :func:`fuzzynav.filters.runner.run_filter` needs besides the data.

    ``sigma_override`` replaces the claimed sigma of a sensor's epochs (sensor name ->
    (M, m) array), e.g. with the simulator's true noise.  ``use_sensors`` restricts the
    filter to some sensors (names or kinds, see :func:`select_sensors`; empty = all).
    """

    config: FilterConfig
    adapters: dict = field(default_factory=dict)
    sensor_options: dict = field(default_factory=dict)
    sigma_override: dict = field(default_factory=dict)
    use_sensors: tuple = ()

    def sensors_for(self, sensors: dict) -> dict:
        """The sensor streams as this filter sees them (subset and sigma overrides applied)."""
        if self.use_sensors:
            sensors = select_sensors(sensors, self.use_sensors)
        return {nm: replace(d, sigma=self.sigma_override[nm]) if nm in self.sigma_override
                else d for nm, d in sensors.items()}


def select_sensors(sensors: dict, wanted) -> dict:
    """The streams of ``sensors`` whose name or kind is in ``wanted`` (a name or a list).

    The same sensor groups serve single filters restricted to a subset (the ``sensors``
    option of every named filter) and the local filters of a filter bank.  A wanted entry
    that matches no stream is an error (a typo would otherwise drop a sensor silently).
    """
    from fuzzynav.errors import FuzzynavError

    wanted = (wanted,) if isinstance(wanted, str) else tuple(wanted)
    for w in wanted:
        if not any(w in (nm, d.kind) for nm, d in sensors.items()):
            have = ", ".join(f"{nm} ({d.kind})" for nm, d in sorted(sensors.items()))
            raise FuzzynavError(f"sensors: no sensor named or of kind {w!r} in this run "
                                f"(sensors: {have or 'none'})")
    return {nm: d for nm, d in sensors.items() if nm in wanted or d.kind in wanted}


@dataclass(frozen=True)
class NamedFilter:
    name: str
    description: str
    make: Callable
    takes_rules: bool = False  # reads rule files (``rules`` option): others refuse them
    takes_params: bool = False  # ``NAME@FILE`` names a tuned-parameter file (``params``)


#: the one catalog: the generic families here, then every paper folder's ``filters.py``
FILTERS = Registry("filter", "fuzzynav.filters",
                   ("catalog", "bank_named", "baselines", "supervisor_named"),
                   paper_module="filters")


def register_filter(name: str, description: str, takes_rules: bool = False,
                    takes_params: bool = False):
    """Decorator registering ``make(context) -> FilterSetup`` under ``name``.

    Every named filter takes the option ``sensors`` (sensor names or kinds): it then sees
    and uses only those streams (:func:`select_sensors`).
    """

    def deco(fn):
        FILTERS.add(name, NamedFilter(name, description, _with_sensor_subset(fn), takes_rules,
                                      takes_params))
        return fn

    return deco


def _with_sensor_subset(make):
    def wrapped(ctx: FilterContext) -> FilterSetup:
        wanted = ctx.options.get("sensors")
        if not wanted:
            return make(ctx)
        wanted = (wanted,) if isinstance(wanted, str) else tuple(wanted)
        sub = replace(ctx, sensors=select_sensors(ctx.sensors, wanted))
        return replace(make(sub), use_sensors=wanted)

    return wrapped


def register_alias(alias: str, name: str) -> None:
    """Register ``alias`` as another name of the filter ``name`` (listed as an alias)."""
    target = FILTERS[name]
    FILTERS.add(alias, NamedFilter(alias, f"alias of {name!r}", target.make,
                                   target.takes_rules, target.takes_params))


def parse_filter_spec(spec: str):
    """``NAME`` or ``NAME@RULES[+RULES...]`` -> ``(name, options)``.

    The second form runs a named filter with its own rule files, so that one comparison can
    hold, say, ``fakf`` (the paper's rules) and ``fakf@rules/paper000_rscale_tuned.json``.
    For a filter with tuned parameters (``ekf-tuned@FILE``) the file is its ``params``.
    """
    name, at, rules = spec.partition("@")
    if at and not rules.strip("+ "):
        raise FuzzynavError(f"{brief(spec)}: no file after '@' (NAME@FILE, or NAME alone for "
                            "the filter's default)")
    target = FILTERS.load().get(name) if rules else None
    if target is not None and target.takes_params:
        return name, {"params": rules}
    return name, ({"rules": [r for r in rules.split("+") if r]} if rules else {})


def get_filter(name: str) -> NamedFilter:
    """The named filter ``name`` (clear error listing the known names)."""
    return FILTERS.lookup(name)


def list_filters() -> list[NamedFilter]:
    """All registered named filters, sorted by name."""
    FILTERS.load()
    return [FILTERS[k] for k in sorted(FILTERS)]


def config_from_imu(noise, **overrides) -> FilterConfig:
    """A 15-state configuration matched to nominal IMU noise.

    Biases are random constants whose prior sigma covers the constant bias, the turn-on
    spread and the bias instability; the instability's Gauss-Markov driving noise
    (2 sigma^2 / tau) becomes the random walk that lets the estimate follow it.
    """
    if noise is None:
        return FilterConfig(**overrides)
    g, a = noise.gyro, noise.accel

    def prior(t):
        return math.sqrt(float(np.mean(np.square(t.bias))) + t.bias_sigma**2 + t.gm_sigma**2)

    def walk(t):
        return math.sqrt(t.rrw**2 + (2.0 * t.gm_sigma**2 / t.gm_tau_s if t.gm_sigma else 0.0))

    if getattr(noise, "filter_states", "constant") == "markov":
        return FilterConfig(**{**markov_config(noise), **overrides})
    cfg = dict(gyro_sigma_dph=(max(prior(g) / units.DPH, 1e-3),),
               accel_sigma_ug=(max(prior(a) / units.UG, 1e-1),),
               gyro_rw_dph_psh=(walk(g) / units.DPH_PSH,),
               accel_rw_ug_psqrts=(walk(a) / units.UG,),
               arw_dpsh=max(g.white / units.DPSH, 1e-4),
               vrw_ug_psqrthz=max(a.white / units.UG, 1e-2))
    cfg.update(overrides)
    return FilterConfig(**cfg)


def markov_config(noise) -> dict:
    """Paper 003's 18 states: gyro constant + gyro Gauss-Markov + accelerometer Gauss-Markov.

    The constant gyro block covers the fixed and turn-on bias, the Markov blocks the bias
    instability with its correlation time (steady sigma ``gm_sigma``; the accelerometer's
    fixed and turn-on bias are folded into its Markov block's initial sigma).
    """
    from fuzzynav.filters.error_model import ErrorModel

    g, a = noise.gyro, noise.accel
    const_g = math.sqrt(float(np.mean(np.square(g.bias))) + g.bias_sigma**2)
    accel = math.sqrt(float(np.mean(np.square(a.bias))) + a.bias_sigma**2 + a.gm_sigma**2)
    return dict(model=ErrorModel(gyro_tau_s=(math.inf, g.gm_tau_s), accel_tau_s=(a.gm_tau_s,)),
                gyro_sigma_dph=(max(const_g / units.DPH, 1e-3), max(g.gm_sigma / units.DPH, 1e-3)),
                accel_sigma_ug=(max(accel / units.UG, 1e-1),),
                gyro_rw_dph_psh=(g.rrw / units.DPH_PSH, 0.0), accel_rw_ug_psqrts=(0.0,),
                arw_dpsh=max(g.white / units.DPSH, 1e-4),
                vrw_ug_psqrthz=max(a.white / units.UG, 1e-2))


def config_overrides(options) -> dict:
    """The filter-configuration keys among a named filter's user ``options``."""
    keys = ("init_att_sigma_deg", "init_vel_sigma_mps", "init_pos_sigma_m", "gate_probability",
            "max_prop_dt_s", "out_rate_hz")
    return {k: options[k] for k in keys if k in options}


def base_config(ctx: FilterContext) -> FilterConfig:
    """The configuration matched to the context's IMU noise, with the user's overrides."""
    return config_from_imu(ctx.imu_noise, **config_overrides(ctx.options))


def every_sensor(ctx: FilterContext, make, config: FilterConfig | None = None) -> FilterSetup:
    """A setup whose every sensor gets its own policy ``make()`` (default: base config)."""
    return FilterSetup(base_config(ctx) if config is None else config,
                       {nm: make() for nm in ctx.sensors})


@register_filter("ekf", "EKF with the nominal noise the sensors and the IMU datasheet claim")
def _ekf(ctx: FilterContext) -> FilterSetup:
    return FilterSetup(base_config(ctx))


@register_filter("ekf-st", "EKF with the state-transformation error model (ST-EKF, Wang et al. 2018)")
def _ekf_st(ctx: FilterContext) -> FilterSetup:
    return FilterSetup(config_from_imu(ctx.imu_noise, **{**config_overrides(ctx.options),
                                                          "error_model": "st"}))
