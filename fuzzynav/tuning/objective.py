"""Score candidate rule sets: RMS errors on cached runs, normalised by a baseline filter.

For each (scenario, seed) of a run set the candidate's RMS position, velocity and attitude
errors are divided by the baseline filter's (the EKF by default) on the same data and the
same initial error; a run's score is the weighted mean of these ratios (1 = as good as the
baseline, lower is better).  A run that loses its covariance scores :data:`FAILED_RATIO`.
Sensor logs and baseline metrics are computed once per process and kept in memory.
"""
from __future__ import annotations

import math

import numpy as np

from fuzzynav.experiment import perturbed_initial_state, run_on_log, setup_for
from fuzzynav.filters.catalog import bind_systems
from fuzzynav.filters.named import FilterSetup
from fuzzynav.filters.runner import run_filter
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from fuzzynav.sim.log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning.config import GROUP_METRICS

def setup_with_systems(log, systems: dict) -> FilterSetup:
    """The EKF configuration of a log with the given fuzzy systems bound to its sensors."""
    base = setup_for(log, "ekf")
    items = [(fis, f"<candidate {name}>") for name, fis in systems.items()]
    return FilterSetup(base.config, bind_systems(items, log.sensors, required=True),
                       base.sensor_options)


#: ratio given to a metric when the candidate's run failed or is not finite
FAILED_RATIO = 10.0


class Evaluator:
    """Runs candidates on a study's training or test runs (one instance per process).

    Parameters
    ----------
    config : StudyConfig
    cache_dir : path or None
        Simulation cache shared by all processes.
    """

    def __init__(self, config, cache_dir=None):
        self.config = config
        self.cache_dir = cache_dir
        self._logs = {}
        self._scenarios = {}
        self._baseline = {}

    # -- data -------------------------------------------------------------------------------
    def log(self, scenario: str, seed: int):
        """The sensor log of a run (simulated once, cached on disk and in memory)."""
        key = (scenario, seed)
        if key not in self._logs:
            if scenario not in self._scenarios:
                self._scenarios[scenario] = load_scenario(scenario)
            self._logs[key] = simulate(self._scenarios[scenario], seed, self.cache_dir)
        return self._logs[key]

    def baseline(self, scenario: str, seed: int) -> dict:
        """Metrics of the baseline filter on a run."""
        key = (scenario, seed)
        if key not in self._baseline:
            self._baseline[key] = run_on_log(self.log(scenario, seed), self.config.baseline,
                                             t_start_s=self.config.t_start_s).metrics
        return self._baseline[key]

    # -- candidates -------------------------------------------------------------------------
    def run_systems(self, systems: dict, scenario: str, seed: int):
        """Run the candidate (controller name -> FuzzySystem) on one run; its outcome."""
        log = self.log(scenario, seed)
        setup = setup_with_systems(log, systems)
        res = run_filter(log.imu, log.sensors, perturbed_initial_state(log, setup),
                         setup.config, setup.adapters, setup.sensor_options)
        metrics = rms_metrics(errors_vs_trajectory(res, log.truth), self.config.t_start_s)
        metrics["completed"] = float(res.ok)
        return res, metrics

    def ratios(self, metrics: dict, scenario: str, seed: int) -> dict:
        """Per-group ratio candidate / baseline (pos, vel, att)."""
        base = self.baseline(scenario, seed)
        out = {}
        for g, key in GROUP_METRICS.items():
            r = metrics[key] / base[key] if base[key] > 0 else math.nan
            out[g] = r if (math.isfinite(r) and metrics.get("completed", 1.0) >= 1.0) \
                else FAILED_RATIO
        return out

    def score(self, ratios: dict) -> float:
        """Weighted mean of the group ratios."""
        w = self.config.weights
        return sum(w[g] * ratios[g] for g in GROUP_METRICS) / sum(w.values())

    def evaluate(self, systems: dict, runs) -> dict:
        """Ratios and score on every run, with their means (no pruning)."""
        per_run = []
        for scenario, seed in runs:
            _, m = self.run_systems(systems, scenario, seed)
            r = self.ratios(m, scenario, seed)
            per_run.append({"scenario": scenario, "seed": seed, **r, "score": self.score(r),
                            **{k: v for k, v in m.items()}})
        means = {g: float(np.mean([p[g] for p in per_run])) for g in (*GROUP_METRICS, "score")}
        return {"runs": per_run, "mean": means}
