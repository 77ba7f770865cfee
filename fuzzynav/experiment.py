"""Run named filters on scenarios and seeds; collect metrics (the layer under CLI and studies).

Every filter in a comparison sees the same sensor logs (simulated once per (scenario, seed)
and cached) and the same initial error, drawn from the filter's initial covariance with a
generator derived from the seed, so differences between filters are paired.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from fuzzynav.errors import UnknownNameError
from fuzzynav.filters.named import FilterContext, FilterSetup, get_filter, parse_filter_spec
from fuzzynav.filters.runner import InitialState, run_filter
from fuzzynav.filters.sensor_states import with_sensor_states
from fuzzynav.metrics import errors_vs_trajectory, improvement_ci, mean_ci, rms_metrics
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.log import SensorLog, component_rng, simulate
from fuzzynav.sim.scenario import Scenario, load_scenario


@dataclass(frozen=True)
class RunOutcome:
    """One filter on one (scenario, seed)."""

    filter: str
    scenario: str
    seed: int
    result: object
    metrics: dict


#: initial states drawn so far, keyed by everything a draw depends on (the seed, the nine
#: initial sigmas, the truth's first sample): every candidate of a study starts its run on a
#: log from the same state, and drawing it costs a generator and four small conversions
_INITIAL = {}
_INITIAL_MAX = 512


def perturbed_initial_state(log: SensorLog, setup: FilterSetup) -> InitialState:
    """Truth at the first sample plus attitude, velocity and position errors from P0."""
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


def filter_context(log, options=None) -> FilterContext:
    """What named filters configure themselves from on a log: a simulated
    :class:`SensorLog`, or a recording run (``log.context``, e.g.
    :class:`fuzzynav.realdata.studyruns.RecordingRun`)."""
    if not isinstance(log, SensorLog):
        return log.context(options)
    return FilterContext(imu_noise=log.scenario.imu.noise_si(), sensors=dict(log.sensors),
                         options=dict(options or {}))


def setup_for(log: SensorLog, filter_name: str, options=None) -> FilterSetup:
    """Configuration and adapters of a named filter for a log (:func:`filter_context`)."""
    ctx = filter_context(log, options)
    return with_sensor_states(get_filter(filter_name).make(ctx), ctx.sensors,
                              ctx.options)


def run_on_log(log: SensorLog, filter_name: str, options=None, t_start_s: float = 0.0,
               setup: FilterSetup | None = None) -> RunOutcome:
    """Run one named filter (or an explicit ``setup``) on a log and score it.

    A recording run (not a :class:`SensorLog`) runs and scores itself (``log.run(setup)``:
    against its reference, in its own time window; ``t_start_s`` does not apply).
    """
    setup = setup or setup_for(log, filter_name, options)
    if not isinstance(log, SensorLog):
        res, metrics = log.run(setup)
        return RunOutcome(filter_name, log.name, log.seed, res, metrics)
    init = perturbed_initial_state(log, setup)
    res = run_filter(log.imu, setup.sensors_for(log.sensors), init, setup.config, setup.adapters,
                     setup.sensor_options)
    metrics = rms_metrics(errors_vs_trajectory(res, log.truth), t_start_s)
    metrics["completed"] = float(res.ok)
    return RunOutcome(filter_name, log.scenario.name, log.seed, res, metrics)


def monte_carlo(scenario, filters, seeds, options=None, cache_dir=None, t_start_s=0.0,
                progress=False) -> pd.DataFrame:
    """Metrics of every filter on every seed, one row per (filter, seed).

    Parameters
    ----------
    scenario : Scenario or str
        A scenario object, a built-in name or a TOML path.
    filters : sequence of str
        Named filters, or ``NAME@RULES[+RULES]`` (a named filter with its own rule files);
        per-filter options may be given as ``options[name]`` (a dict) in addition to shared
        options.
    seeds : sequence of int
    options : dict, optional
        Shared filter options; ``options[filter_name]`` (dict) overrides per filter.
    cache_dir : path, optional
        Where simulated logs are cached.
    """
    scn = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    options = dict(options or {})
    rows = []
    seeds = list(seeds)
    bar = _progress(len(seeds) * len(filters), progress, f"{scn.name}")
    for seed in seeds:
        log = simulate(scn, int(seed), cache_dir)
        for name in filters:
            base, own = parse_filter_spec(name)
            opts = {k: v for k, v in options.items() if not isinstance(v, dict)}
            opts.update(options.get(name, {}) if isinstance(options.get(name), dict) else {})
            opts.update(own)
            out = run_on_log(log, base, opts, t_start_s)
            rows.append({"scenario": scn.name, "filter": name, "seed": int(seed), **out.metrics})
            bar.update(1)
    bar.close()
    return pd.DataFrame(rows)


def _progress(total, enabled, desc):
    from tqdm.auto import tqdm

    return tqdm(total=total, disable=not enabled, desc=desc, unit="run", leave=False)


def summary_table(df: pd.DataFrame, metrics, baseline: str | None = None) -> pd.DataFrame:
    """Mean with 95 % CI per filter and metric, and paired improvement over ``baseline``.

    Returns a table indexed by metric with, per filter, ``mean``, ``ci`` (half width) and,
    for non-baseline filters, ``improvement_pct`` with ``improvement_lo`` / ``_hi``.

    Raises
    ------
    UnknownNameError
        (a ``KeyError``) for a ``baseline`` not among the filters of ``df`` or a metric
        that is not one of its columns.
    """
    out = {}
    filters = list(dict.fromkeys(df["filter"]))
    # names the caller typed: one clear error instead of pandas' bare KeyError
    if baseline is not None and baseline not in filters:
        raise UnknownNameError("baseline filter", baseline, filters)
    for m in metrics:
        if m not in df.columns or m in ("scenario", "filter", "seed"):
            raise UnknownNameError("metric", m, [c for c in df.columns
                                                 if c.startswith(("rms_", "max_"))])
    for m in metrics:
        row = {}
        piv = df.pivot_table(index="seed", columns="filter", values=m)
        for f in filters:
            est = mean_ci(piv[f].to_numpy())
            row[(f, "mean")], row[(f, "ci")] = est.mean, est.half_width
            if baseline is not None and f != baseline:
                imp = improvement_ci(piv[baseline].to_numpy(), piv[f].to_numpy())
                row[(f, "improvement_pct")] = imp.mean
                row[(f, "improvement_lo")], row[(f, "improvement_hi")] = imp.lo, imp.hi
        out[m] = row
    table = pd.DataFrame(out).T
    table.columns = pd.MultiIndex.from_tuples(table.columns)
    return table
