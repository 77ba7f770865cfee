"""Error states that an aiding sensor brings along (a DVL's scale factor and misalignment).

A measurement-model module registers, per sensor kind, the state blocks it can estimate
(:func:`register_states`).  :func:`add_sensor_states` appends them to any named filter's
configuration for the sensors of a run and tells the model where they sit (its
``state_start`` option), so every filter of a comparison (``ekf``, ``ekf-st``, ``huber``,
...) estimates the same states.  The filter option ``sensor_states = false`` turns it off.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable

from fuzzynav.filters import measurements
from fuzzynav.filters.error_model import ErrorModel

#: sensor kind -> ``blocks(options) -> [(block kind, tau_s, sigma, noise density), ...]``
_STATES: dict[str, Callable] = {}


def register_states(kind: str, blocks: Callable) -> None:
    """Register the state blocks a sensor kind brings (called by its measurement module)."""
    _STATES[kind] = blocks


def add_sensor_states(setup, sensors: dict, options=None):
    """``setup`` with the registered states of every sensor appended to its error model.

    Parameters
    ----------
    setup : FilterSetup
    sensors : dict
        Sensor name -> SensorData of the run (sorted by name for a stable layout).
    options : dict, optional
        Filter options; ``sensor_states`` (default True) switches this off, the rest is
        passed to the kinds' block functions (e.g. ``dvl_scale_sigma``).

    Returns
    -------
    FilterSetup
        With ``config.model.extra`` and ``config.extra_noise_si`` extended and
        ``sensor_options[name]["state_start"]`` set; unchanged when no sensor has states or
        the blocks are there already.
    """
    options = dict(options or {})
    if not options.get("sensor_states", True):
        return setup
    cfg = setup.config
    extra, noise = list(cfg.model.extra), list(cfg.extra_noise_si)
    sensor_opts = {k: dict(v) for k, v in setup.sensor_options.items()}
    taken = {nm for nm, _ in extra}
    for i, name in enumerate(sorted(sensors)):
        kind = sensors[name].kind
        measurements.get(kind)  # imports the model module, which registers its states
        if kind not in _STATES:
            continue
        starts = {}
        for block, tau, sigma, q in _STATES[kind](options):
            nm = block if block not in taken else f"{block}:{name}"
            extra.append((nm, tau))
            noise.append((sigma, q))
            taken.add(nm)
            starts[block] = nm
        sensor_opts.setdefault(name, {})["_blocks"] = starts
    if len(extra) == len(cfg.model.extra):
        return setup
    model = ErrorModel(cfg.model.gyro_tau_s, cfg.model.accel_tau_s, tuple(extra))
    layout = model.layout
    for opts in sensor_opts.values():
        if "_blocks" in opts:
            opts["state_start"] = {b: layout.start(nm) for b, nm in opts.pop("_blocks").items()}
    return replace(setup, config=cfg.with_(model=model, extra_noise_si=tuple(noise)),
                   sensor_options=sensor_opts)
