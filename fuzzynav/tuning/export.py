"""Export a study's best trial (or a chosen one) as ``fuzzynav-fis`` rule files.

One file per controller: ``--out rules/NAME.json`` writes ``NAME.json`` for a single
controller and ``NAME_<controller>.json`` for several.  Each file carries a ``provenance``
block (study, trial, sampler, objective values, train/test runs, held-out result, package
version, date) and an ``expected`` block: the metrics that ``fakf`` with these files (reloaded
from disk) gives on the first test run — the regression tests re-run it.
"""
from __future__ import annotations

import datetime as _dt
import math
from pathlib import Path

import optuna
from optuna.trial import TrialState

from fuzzynav import __version__
from fuzzynav.errors import FuzzynavError
from fuzzynav.fileio import staged
from fuzzynav.experiment import run_on_log
from fuzzynav.fuzzy import FuzzySystem, load_fis, save_fis
from fuzzynav.tuning.evaluate import run_table, summary
from fuzzynav.tuning.objective import Evaluator
from fuzzynav.tuning.space import ControllerSpace, build_all
from fuzzynav.tuning.optuna_study import best_trials

__all__ = ["EXPECTED_METRICS", "choose_trial", "systems_of", "export_rules"]

#: metrics recorded in ``expected`` (and compared by the regression tests)
EXPECTED_METRICS = ("rms_pos_m", "rms_vel_mps", "rms_att_deg", "rms_pos_e_m", "rms_pos_n_m",
                    "rms_pos_u_m", "rms_heading_deg")


def choose_trial(study, cfg, trial_number=None, pareto_index=None):
    """The trial to export: a given number, a Pareto member, or the best fully run one."""
    if pareto_index is not None and not cfg.multi_objective:
        raise FuzzynavError(f"--pareto: study {cfg.name!r} is single-objective (it has no "
                            "Pareto front); export its best trial, or a given one with --trial")
    if pareto_index is not None and trial_number is not None:
        raise FuzzynavError("--trial and --pareto each choose the trial: give one of them")
    if trial_number is not None:
        trials = study.get_trials(deepcopy=False)
        if not 0 <= trial_number < len(trials):
            raise FuzzynavError(f"study {cfg.name!r} has no trial {trial_number} "
                                f"(trials 0..{len(trials) - 1})")
        trial = trials[trial_number]
        if trial.state != TrialState.COMPLETE:
            raise FuzzynavError(f"study {cfg.name!r}: trial {trial_number} is "
                                f"{trial.state.name}, not COMPLETE; nothing to export")
        return trial
    best = best_trials(study, cfg)
    if not best:
        raise FuzzynavError(f"study {cfg.name!r} has no complete trial that ran every "
                            "training run yet")
    if cfg.multi_objective:
        best = sorted(best, key=lambda t: tuple(t.values))
        k = pareto_index or 0
        if not 0 <= k < len(best):
            raise FuzzynavError(f"--pareto must be in 0..{len(best) - 1}")
        return best[k]
    return best[0]


def systems_of(cfg, trial) -> dict:
    """Controller name -> fuzzy system of a stored trial."""
    spaces = [ControllerSpace.from_config(c) for c in cfg.controllers]
    return build_all(spaces, optuna.trial.FixedTrial(trial.params, trial.number))


def _paths(out, names):
    out = Path(out)
    if out.suffix != ".json":
        raise FuzzynavError(f"{out}: the output must be a .json rule file")
    if len(names) == 1:
        return {names[0]: out}
    return {n: out.with_name(f"{out.stem}_{n}.json") for n in names}


def _with(fis: FuzzySystem, **blocks) -> FuzzySystem:
    d = fis.to_dict()
    d.update({k: v for k, v in blocks.items() if v is not None})
    return load_fis(d)


def export_rules(cfg, study, out, trial_number=None, pareto_index=None, cache_dir=None,
                 progress=False) -> list[Path]:
    """Write the rule files of a trial with provenance and expected metrics.

    The files are written complete (with their ``expected`` block) into a temporary
    directory beside ``out`` and then moved into place together
    (:func:`fuzzynav.fileio.staged`): an error leaves no partial file, and a read-only
    directory or a full disk is one :class:`~fuzzynav.errors.OutputError` with the old
    files unchanged.
    """
    trial = choose_trial(study, cfg, trial_number, pareto_index)
    systems = systems_of(cfg, trial)
    paths = _paths(out, list(systems))
    ev = Evaluator(cfg, cache_dir)
    test = run_table(ev, systems, cfg.test)
    held_out = summary(test).iloc[0].to_dict() if not test.empty else {}
    created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()
    with staged(next(iter(paths.values())).parent, "rule file") as tmp:
        files = {name: tmp / p.name for name, p in paths.items()}
        for name, fis in systems.items():
            prov = {
                "study": cfg.name, "config": str(cfg.path) if cfg.path else None,
                "trial": trial.number, "sampler": cfg.sampler, "controller": name,
                "template": str(next(c.template for c in cfg.controllers if c.name == name)),
                "objective": {"value": list(trial.values) if cfg.multi_objective
                              else trial.value,
                              "ratios_to_" + cfg.baseline: _finite(trial.user_attrs.get(
                                  "ratios")),
                              "weights": cfg.weights},
                "train": [list(r) for r in cfg.train], "test": [list(r) for r in cfg.test],
                "held_out_ratios_to_" + cfg.baseline: {
                    k: float(v) for k, v in held_out.items()
                    if (k.endswith("ratio") or k == "score") and math.isfinite(v)},
                "package_version": __version__, "created": created,
            }
            save_fis(_with(fis, provenance=prov), files[name])
        _write_expected(cfg, files, ev)
    return list(paths.values())


def _finite(ratios):
    """The ratios that are numbers (a study on recordings has no attitude ratio: NaN,
    which JSON cannot hold)."""
    return None if ratios is None else {k: v for k, v in ratios.items() if math.isfinite(v)}


def _write_expected(cfg, paths: dict, ev: Evaluator) -> None:
    """Run the study's filter (``fakf`` unless ``[objective] filter``) with the files as
    written and record what it gives on the first simulated test run (else training run):
    the regression test then needs no recording.  A study on recordings alone, or whose
    simulated runs are all too long to hold whole (its ``[streaming]`` table), writes no
    ``expected`` block."""
    from fuzzynav.realdata.dataspec import is_recording_name
    from fuzzynav.sim.scenario import load_scenario

    simulated = [r for r in cfg.test + cfg.train if not is_recording_name(r[0])
                 and (cfg.streaming is None or cfg.streaming.holds(load_scenario(r[0])))]
    if not simulated:
        return
    scenario, seed = simulated[0]
    files = [str(p) for p in paths.values()]
    out = run_on_log(ev.log(scenario, seed), cfg.filter, {"rules": files},
                     t_start_s=cfg.t_start_s)
    metrics = {k: out.metrics[k] for k in EXPECTED_METRICS}
    for name, path in paths.items():
        others = [p.name for n, p in paths.items() if n != name]
        expected = {"scenario": scenario, "seed": seed, "filter": cfg.filter,
                    "with_rules": others, "t_start_s": cfg.t_start_s, "metrics": metrics}
        save_fis(_with(load_fis(path), expected=expected), path)
