"""What each library patch and per-run memo saves a study run, each against running without it.

One study run is ``run_filter`` and ``errors_vs_trajectory`` of the ``fakf`` filter on a
``paper000`` log (755 s at 100 Hz, 1-Hz GPS, 5-Hz imaging polarization), warm kernels,
every run on the same log as a study's runs are.  Each variant turns one shortcut off:

* numba typing a kernel table from scratch (``numba_patch_dispatch.memoise_table_types``);
* numba's own kernel-address lookups (``numba_patch_dispatch.memoise_kernel_addresses``);
* the IMU clock's interval, the truth at the result's epochs, the polarization extra
  columns recomputed every run (the three :class:`~fuzzynav.live_cache.LiveCache` memos).

The variants are interleaved (``--rounds`` rounds of ``--runs`` runs each, the order reversed
every other round) and the median per-run time of each is reported with its saving against
the shipped path; the results of every variant are checked bit-identical to the shipped one.
The Wilcoxon pruner's decision (``optuna_patch_pruners``) is timed against Optuna's own on a
study of ``paper000_tune``'s size (rule tables of both controllers).

Usage: ``python benchmarks/bench_patches.py [--rounds 7] [--runs 5] [--no-write]``.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numba as nb
import numpy as np
import optuna

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav import metrics  # noqa: E402
from fuzzynav.experiment import perturbed_initial_state, setup_for  # noqa: E402
from fuzzynav.filters import loop, numba_patch_dispatch as patch, runner  # noqa: E402
from fuzzynav.filters.measurements import polarization_rows  # noqa: E402
from fuzzynav.sim.log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402
from fuzzynav.tuning.optuna_patch_pruners import WilcoxonPruner  # noqa: E402


def _loop_dispatchers():
    return [d for d in vars(loop).values()
            if isinstance(d, nb.core.dispatcher.Dispatcher) and "typeof_pyval" in vars(d)]


class _Off:
    """Context of one variant: ``off()`` before each run, ``on()`` after the variant."""

    def __init__(self, off=lambda: None, on=lambda: None):
        self.off, self.on = off, on


def _variants():
    typing = {d: vars(d)["typeof_pyval"] for d in _loop_dispatchers()}

    def typing_off():
        for d in typing:
            vars(d).pop("typeof_pyval", None)

    def typing_on():
        for d, f in typing.items():
            d.typeof_pyval = f

    return {
        "shipped (every shortcut)": _Off(),
        "kernel tables typed by numba each run": _Off(typing_off, typing_on),
        "numba's own kernel-address lookups": _Off(patch.restore_kernel_addresses,
                                                   patch.memoise_kernel_addresses),
        "IMU clock interval recomputed": _Off(runner._CLOCKS.clear),
        "truth at the epochs recomputed": _Off(metrics._TRUTH_AT.clear),
        "polarization extra columns recomputed": _Off(polarization_rows._KEPT.clear),
    }


def study_run(log, setup, init, sensors):
    res = runner.run_filter(log.imu, sensors, init, setup.config, setup.adapters)
    return res, metrics.errors_vs_trajectory(res, log.truth)


def time_runs(rounds: int, runs: int):
    log = simulate(load_scenario("paper000"), 0, tempfile.mkdtemp())
    setup = setup_for(log, "fakf")
    init = perturbed_initial_state(log, setup)
    sensors = setup.sensors_for(log.sensors)
    ref_res, ref_err = study_run(log, setup, init, sensors)
    variants = _variants()
    times = {name: [] for name in variants}
    names = list(variants)
    for r in range(rounds):
        for name in (names if r % 2 == 0 else names[::-1]):
            v = variants[name]
            v.off()
            study_run(log, setup, init, sensors)  # the variant's first run, not counted
            per = []
            for _ in range(runs):
                v.off()
                t0 = time.perf_counter()
                res, err = study_run(log, setup, init, sensors)
                per.append(time.perf_counter() - t0)
            v.on()
            for a, b in ((res.lla, ref_res.lla), (res.sigma, ref_res.sigma),
                         (err.pos_m, ref_err.pos_m), (err.att_rad, ref_err.att_rad)):
                if not np.array_equal(a, b):
                    raise RuntimeError(f"{name}: results differ from the shipped path")
            times[name].append(statistics.median(per))
    return times, log.imu.n_samples


def _pruner_study(n_params: int, n_trials: int, n_steps: int, rng):
    dist = optuna.distributions.FloatDistribution(0.0, 1.0)
    study = optuna.create_study(storage=optuna.storages.InMemoryStorage())
    for _ in range(n_trials):
        steps = rng.uniform(0.5, 1.5, n_steps)
        study.add_trial(optuna.trial.create_trial(
            value=float(steps.mean()), params={f"p{i}": 0.5 for i in range(n_params)},
            distributions={f"p{i}": dist for i in range(n_params)},
            intermediate_values=dict(enumerate(steps))))
    trial = optuna.trial.create_trial(
        state=optuna.trial.TrialState.RUNNING, params={f"p{i}": 0.5 for i in range(n_params)},
        distributions={f"p{i}": dist for i in range(n_params)},
        intermediate_values=dict(enumerate(rng.uniform(0.5, 1.5, n_steps) + 0.1)))
    return study, trial


def time_pruners(n_params: int, rounds: int, calls: int = 200):
    study, trial = _pruner_study(n_params, 60, 9, np.random.default_rng(0))
    ours = WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)
    theirs = optuna.pruners.WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)
    assert ours.prune(study, trial) == theirs.prune(study, trial)
    out = {"fuzzynav (uncopied best trial)": [], "Optuna's (copies the best trial)": []}
    for r in range(rounds):
        for name, pr in ((("fuzzynav (uncopied best trial)", ours),
                          ("Optuna's (copies the best trial)", theirs))[::1 - 2 * (r % 2)]):
            t0 = time.perf_counter()
            for _ in range(calls):
                pr.prune(study, trial)
            out[name].append((time.perf_counter() - t0) / calls)
    return out


def n_study_params() -> int:
    """Parameters of a ``paper000_tune`` trial (its search space, both controllers)."""
    from fuzzynav.tuning.config import load_study_config
    from fuzzynav.tuning.space import ControllerSpace, build_all

    cfg = load_study_config(Path(__file__).resolve().parents[1] / "studies"
                            / "paper000_tune.toml")
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    trial = study.ask()
    build_all([ControllerSpace.from_config(c) for c in cfg.controllers], trial)
    return len(trial.params)


def report(times, n_imu, prune, n_params, args) -> str:
    base = statistics.median(times["shipped (every shortcut)"])
    lines = ["## Library patches and per-run memos (`benchmarks/bench_patches.py`)", "",
             f"One study run (`run_filter` + `errors_vs_trajectory`, `fakf` on `paper000` seed "
             f"0, {n_imu} IMU samples, warm kernels, the same log every run), each shortcut "
             f"turned off in turn: {args.rounds} interleaved rounds of {args.runs} runs, "
             "median per run; every variant's results checked bit-identical to the shipped "
             f"path. Machine: {machine()}; Optuna {optuna.__version__}.", "",
             "| variant | ms per run (median) | cost of going without (ms per run) | per round |",
             "|---|---|---|---|"]
    for name, vals in times.items():
        m = statistics.median(vals)
        lines.append(f"| {name} | {m * 1e3:.2f} | {(m - base) * 1e3:+.2f} | "
                     + ", ".join(f"{v * 1e3:.2f}" for v in vals) + " |")
    lines += ["", f"Wilcoxon pruner, one decision against a study of 60 complete trials of "
              f"{n_params} parameters and 9 steps each (a `paper000_tune` trial's size), "
              f"{args.rounds} interleaved rounds of 200 decisions:", "",
              "| pruner | µs per decision (median) | per round |", "|---|---|---|"]
    for name, vals in prune.items():
        lines.append(f"| {name} | {statistics.median(vals) * 1e6:.0f} | "
                     + ", ".join(f"{v * 1e6:.0f}" for v in vals) + " |")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--no-write", action="store_true", help="print, leave docs/ alone")
    args = ap.parse_args(argv)
    times, n_imu = time_runs(args.rounds, args.runs)
    n_params = n_study_params()
    prune = time_pruners(n_params, args.rounds)
    text = report(times, n_imu, prune, n_params, args)
    print(text)
    if not args.no_write:
        write_section("patches", text)


if __name__ == "__main__":
    main()
