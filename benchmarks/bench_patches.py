"""What each library patch and per-run memo saves a study run, each against running without it.

One study run is ``run_filter`` and ``errors_vs_trajectory`` of the ``fakf`` filter on a
``paper000`` log (755 s at 100 Hz, 1-Hz GPS, 5-Hz imaging polarization), warm kernels,
every run on the same log as a study's runs are.  Each variant turns one shortcut off:

* numba typing a tuple holding kernels (a kernel table, the bank) from scratch
  (``numba_patch_dispatch.memoise_table_types``);
* numba's own kernel-address lookups (``numba_patch_dispatch.memoise_kernel_addresses``);
* the truth at the result's epochs and the polarization extra columns recomputed every
  run (the two :class:`~fuzzynav.live_cache.LiveCache` memos).

The variants are interleaved (``--rounds`` rounds of ``--runs`` runs each, the order reversed
every other round) and the median per-run time of each is reported with its saving against
the shipped path; the results of every variant are checked bit-identical to the shipped one.
Optuna's Wilcoxon pruner is timed against the same pruner handed the best trial uncopied
(through Optuna's private ``Study._get_best_trial(deepcopy=False)``: the patch fuzzynav
shipped until this measurement showed it saved under 1 % of a trial, and removed) on a
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
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402


class _BestUncopied:
    """A study whose ``best_trial`` is the stored trial, not a copy (the removed patch)."""

    def __init__(self, study):
        self._study = study

    def __getattr__(self, name):
        return getattr(self._study, name)

    @property
    def best_trial(self):
        return self._study._get_best_trial(deepcopy=False)


class _UncopiedWilcoxon(optuna.pruners.WilcoxonPruner):
    def prune(self, study, trial) -> bool:
        return super().prune(_BestUncopied(study), trial)


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
        "tuples holding kernels typed by numba each run": _Off(typing_off, typing_on),
        "numba's own kernel-address lookups": _Off(patch.restore_kernel_addresses,
                                                   patch.memoise_kernel_addresses),
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
                t0 = time.process_time()  # CPU time: others' load shows less than in wall time
                res, err = study_run(log, setup, init, sensors)
                per.append(time.process_time() - t0)
            v.on()
            for a, b in ((res.lla, ref_res.lla), (res.sigma, ref_res.sigma),
                         (err.pos_m, ref_err.pos_m), (err.att_rad, ref_err.att_rad)):
                if not np.array_equal(a, b):
                    raise RuntimeError(f"{name}: results differ from the shipped path")
            times[name].append(statistics.median(per))
    return times, log.imu.n_samples, time_components(log, setup, init, sensors)


def _cpu_ms(f, clear=lambda: None, n=30):
    """Median CPU milliseconds of ``f()``, ``clear()`` before each call."""
    out = []
    for _ in range(n):
        clear()
        t0 = time.process_time()
        f()
        out.append(time.process_time() - t0)
    return statistics.median(out) * 1e3


def _seen_in_a_run(run):
    """The tuples holding kernels the loop typed (its kernel tables, its bank) and the
    (function, signature) pairs whose addresses numba looked up during ``run()``, with the
    patches on."""
    import numba.experimental.function_type as ft

    tables, pairs, saved = [], [], {}
    for d in _loop_dispatchers():
        memo = saved[d] = vars(d)["typeof_pyval"]
        d.typeof_pyval = lambda v, memo=memo: (tables.append(v) if isinstance(v, tuple)
                                               else None, memo(v))[1]
    names = ("_get_wrapper_address", "_get_jit_address")
    looked = {n: getattr(ft, n) for n in names}
    for n in names:
        setattr(ft, n, lambda f, sig, n=n: (pairs.append((n, f, sig)), looked[n](f, sig))[1])
    try:
        run()
    finally:
        for d, memo in saved.items():
            d.typeof_pyval = memo
        for n in names:
            setattr(ft, n, looked[n])
    return tables, pairs


def time_components(log, setup, init, sensors) -> dict:
    """CPU ms per run of the work each shortcut spares: with it, and without it."""
    import numba.experimental.function_type as ft

    res, _ = study_run(log, setup, init, sensors)
    tables, pairs = _seen_in_a_run(lambda: study_run(log, setup, init, sensors))
    disp = _loop_dispatchers()[0]
    plain_type = type(disp).typeof_pyval

    def typing(fn):
        return lambda: [fn(t) for t in tables]

    def lookups(own):
        return lambda: [(getattr(ft, n).wrapped if own else getattr(ft, n))(f, sig)
                        for n, f, sig in pairs]

    pol = next(d for d in sensors.values() if d.kind == "polarization")
    return {
        f"tuples holding kernels typed ({len(tables)} per run)":
            (_cpu_ms(typing(vars(disp)["typeof_pyval"])),
             _cpu_ms(typing(lambda t: plain_type(disp, t)))),
        f"kernel addresses looked up ({len(pairs)} per run)":
            (_cpu_ms(lookups(False)), _cpu_ms(lookups(True))),
        "truth at the epochs (`errors_vs_trajectory`)":
            (_cpu_ms(lambda: metrics.errors_vs_trajectory(res, log.truth)),
             _cpu_ms(lambda: metrics.errors_vs_trajectory(res, log.truth),
                     metrics._TRUTH_AT.clear)),
        "polarization rows (`polarization_rows.rows`)":
            (_cpu_ms(lambda: polarization_rows.rows(pol)),
             _cpu_ms(lambda: polarization_rows.rows(pol), polarization_rows._KEPT.clear)),
    }


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
    ours = _UncopiedWilcoxon(p_threshold=0.1, n_startup_steps=2)
    theirs = optuna.pruners.WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)
    assert ours.prune(study, trial) == theirs.prune(study, trial)
    out = {"best trial uncopied (private API; removed)": [], "Optuna's own (copies the best trial; shipped)": []}
    for r in range(rounds):
        for name, pr in ((("best trial uncopied (private API; removed)", ours),
                          ("Optuna's own (copies the best trial; shipped)", theirs))[::1 - 2 * (r % 2)]):
            t0 = time.process_time()
            for _ in range(calls):
                pr.prune(study, trial)
            out[name].append((time.process_time() - t0) / calls)
    return out


def n_study_params() -> int:
    """Parameters of a ``paper000_tune`` trial (its search space, both controllers)."""
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.space import ControllerSpace, build_all

    cfg = load_study_config(Path(__file__).resolve().parents[1] / "studies"
                            / "paper000_tune.toml")
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    trial = study.ask()
    build_all([ControllerSpace.from_config(c) for c in cfg.controllers], trial)
    return len(trial.params)


def report(times, n_imu, parts, prune, n_params, args) -> str:
    shipped = times["shipped (every shortcut)"]
    base = statistics.median(shipped)
    lines = ["## Library patches and per-run memos (`benchmarks/bench_patches.py`)", "",
             f"One study run (`run_filter` + `errors_vs_trajectory`, `fakf` on `paper000` seed "
             f"0, {n_imu} IMU samples, warm kernels, the same log every run), each shortcut "
             f"turned off in turn: {args.rounds} interleaved rounds of {args.runs} runs, "
             "median CPU time per run, the cost of going without taken against the shipped "
             "path round by round; every variant's results checked bit-identical to the "
             f"shipped path. Machine: {machine()}; Optuna {optuna.__version__}.", "",
             "| variant | CPU ms per run (median) | going without costs (ms per run, median "
             "of rounds) | relative | per round (ms) |", "|---|---|---|---|---|"]
    for name, vals in times.items():
        diffs = [v - b for v, b in zip(vals, shipped)]
        d = statistics.median(diffs)
        lines.append(f"| {name} | {statistics.median(vals) * 1e3:.2f} | {d * 1e3:+.2f} | "
                     f"{1 + d / base:.3f} | " + ", ".join(f"{x * 1e3:+.2f}" for x in diffs)
                     + " |")
    lines += ["", "The work each shortcut spares, timed alone on the same run's inputs (median "
              "CPU time of 30 calls; precise where the whole runs above are noisy):", "",
              "| per run | CPU ms with the shortcut | without | spared |", "|---|---|---|---|"]
    for name, (on, off) in parts.items():
        lines.append(f"| {name} | {on:.3f} | {off:.3f} | {off - on:.3f} |")
    lines += ["", "Kept: the typing memo of tuples holding kernels, the address memo "
              "(`fuzzynav/filters/numba_patch_dispatch.py`) and the two `LiveCache` memos. "
              "Removed on 2026-12-03, after this benchmark measured them: the memo of the IMU "
              "clock's interval (~0.2 ms of a run) and the pruner reading the best trial "
              "uncopied (below).",
              "", f"Wilcoxon pruner, one decision against a study of 60 complete trials of "
              f"{n_params} parameters and 9 steps each (a `paper000_tune` trial's size), "
              f"{args.rounds} interleaved rounds of 200 decisions:", "",
              "| pruner | CPU µs per decision (median) | per round |", "|---|---|---|"]
    for name, vals in prune.items():
        lines.append(f"| {name} | {statistics.median(vals) * 1e6:.0f} | "
                     + ", ".join(f"{v * 1e6:.0f}" for v in vals) + " |")
    spared = statistics.median([a - b for a, b in zip(*reversed(list(prune.values())))])
    lines += ["", f"A trial reports at most 9 steps, so the uncopied best trial would spare at "
              f"most {9 * spared * 1e3:.2f} ms of a trial of 9 runs "
              f"(~{9 * base * 1e3:.0f} ms of CPU at the run time above)."]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--no-write", action="store_true", help="print, leave docs/ alone")
    args = ap.parse_args(argv)
    times, n_imu, parts = time_runs(args.rounds, args.runs)
    n_params = n_study_params()
    prune = time_pruners(n_params, args.rounds)
    text = report(times, n_imu, parts, prune, n_params, args)
    print(text)
    if not args.no_write:
        write_section("patches", text)


if __name__ == "__main__":
    main()
