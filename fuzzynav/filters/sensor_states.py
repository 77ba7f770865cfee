"""State blocks asked for by measurement models (a log's scale factor, a DVL's misalignment).

A measurement model may declare ``states(sensor_data, options)``: the blocks it estimates.
:func:`with_sensor_states` appends them to a filter setup's error model (after the blocks
already there), gives them their initial sigma and driving noise, and tells the model where
they are through ``sensor_options[name]["state_start"]`` (block kind -> first state index),
which its ``pack`` function turns into kernel constants.  A second sensor asking for a block
of the same kind gets its own block, tagged with the sensor's name (``log_bias:log2``).
"""
from __future__ import annotations

import math
from dataclasses import replace

from fuzzynav.filters import measurements

__all__ = ["with_sensor_states"]


def _noise(tau_s: float, sigma0: float, steady: float) -> tuple:
    """``(initial sigma, driving-noise density)``: 2 steady^2 / tau for Gauss-Markov."""
    q = 0.0 if math.isinf(tau_s) else 2.0 * steady * steady / tau_s
    return (float(sigma0), q)


def with_sensor_states(setup, sensors: dict, filter_options=None):
    """``setup`` (a :class:`~fuzzynav.filters.named.FilterSetup`) with the sensors' blocks.

    Parameters
    ----------
    setup : FilterSetup
    sensors : mapping name -> SensorData
    filter_options : dict, optional
        The named filter's options: ``sensor_states = False`` adds nothing (e.g. the A-KIT
        runs); the others (e.g. ``dvl_scale_sigma``) reach every model's ``states``, under
        the sensor's own ``sensor_options``.

    Returns
    -------
    FilterSetup
        The same setup when no model asks for states.
    """
    filter_options = dict(filter_options or {})
    if not filter_options.get("sensor_states", True):
        return setup
    config = setup.config
    extra, noise = list(config.model.extra), list(config.extra_noise_si)
    options = {nm: dict(v) for nm, v in setup.sensor_options.items()}
    names = {nm for nm, _ in extra}
    owned = {}
    for nm in sorted(sensors):
        model = measurements.get(sensors[nm].kind)
        if model.states is None:
            continue
        for block, tau, sigma0, steady in model.states(sensors[nm],
                                                         {**filter_options, **options.get(nm, {})}):
            name = block if block not in names else f"{block}:{nm}"
            names.add(name)
            extra.append((name, float(tau)))
            noise.append(_noise(tau, sigma0, steady))
            owned.setdefault(nm, []).append((block, name))
    if not owned:
        return setup
    model = replace(config.model, extra=tuple(extra))
    config = config.with_(model=model, extra_noise_si=tuple(noise))
    for nm, blocks in owned.items():
        options.setdefault(nm, {})["state_start"] = {b: model.layout.start(name)
                                                      for b, name in blocks}
    return replace(setup, config=config, sensor_options=options)
