"""What every run source on a simulated log shares: its filter context, the initial error
every filter of a comparison starts from, and which metrics must be finite.

Used by :mod:`fuzzynav.experiment` (a whole simulated log) and :mod:`fuzzynav.streamrun`
(a log simulated chunk by chunk) alike, so both start a filter from the same drawn state.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.filters.named import FilterContext, FilterSetup
from fuzzynav.filters.runner import InitialState
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.sensor_log import component_rng

__all__ = ["OnSimulatedLog", "perturbed_initial_state"]


#: initial states drawn so far, keyed by everything a draw depends on (the seed, the nine
#: initial sigmas, the truth's first sample): every candidate of a study starts its run on a
#: log from the same state, and drawing it costs a generator and four small conversions
_INITIAL = {}
_INITIAL_MAX = 512


def perturbed_initial_state(log, setup: FilterSetup) -> InitialState:
    """Truth at the first sample plus attitude, velocity and position errors from P0
    (``log``: a :class:`~fuzzynav.sim.sensor_log.SensorLog`, or anything with its ``seed``
    and a ``truth`` from the run's first sample)."""
    truth = log.truth
    sig = np.sqrt(np.diag(setup.config.P0())[:9])
    first = [np.asarray(a[0], float).tobytes() for a in (truth.lla, truth.vel_n, truth.q_bn)]
    key = (int(log.seed), sig.tobytes(), float(truth.time_s[0]), *first)
    got = _INITIAL.get(key)
    if got is None:
        if len(_INITIAL) >= _INITIAL_MAX:
            _INITIAL.clear()
        got = _INITIAL[key] = _draw_initial_state(log.seed, truth, sig)
    # fresh arrays: a caller may change its copy
    return InitialState(got.time_s, got.lla.copy(), got.vel_n.copy(), got.q_bn.copy())


def _draw_initial_state(seed, truth, sig) -> InitialState:
    """The draw of :func:`perturbed_initial_state` (``sig``: its nine initial sigmas)."""
    x0 = component_rng(seed, "filter-init").normal(0.0, 1.0, 9) * sig
    C0 = (np.eye(3) - attitude.skew(x0[:3])) @ attitude.quat_to_dcm(truth.q_bn[0])
    d = earth.enu_to_delta_lla(x0[6:9], truth.lla[0, 0], truth.lla[0, 2])
    return InitialState(float(truth.time_s[0]), truth.lla[0] + np.array(d),
                        truth.vel_n[0] + x0[3:6], attitude.dcm_to_quat(C0))


class OnSimulatedLog:
    """What every run source on a simulated log (attribute ``log``) shares: its name and
    seed, the filter context of the log, and that every RMS and maximum must be finite."""

    # a scenario file sets its sensors' noise, outages and mounting itself
    SETTINGS = frozenset({"mc", "t_start"})
    KIND = "simulated scenarios"
    SETTINGS_NOTE = ("they take their noise, outages and mounting from the scenario file; "
                     "the recording options need --data")

    @property
    def name(self) -> str:
        return self.log.scenario.name

    @property
    def seed(self) -> int:
        return self.log.seed

    def context(self, options=None) -> FilterContext:
        return FilterContext(imu_noise=self.log.scenario.imu.noise_si(),
                             sensors=dict(self.log.sensors), options=dict(options or {}))

    def required(self, metrics: dict) -> tuple:
        return tuple(m for m in metrics if m.startswith(("rms_", "max_")))
