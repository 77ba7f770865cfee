"""The fuzzy-controller study: ``[[controllers]]`` rule sets searched against the baseline.

One Optuna study per file; a trial is a candidate rule set scored by
:class:`~fuzzynav.tuning.objective.Objective` (ratios of RMS errors to the baseline filter on
the training runs).  Summary, export and report are :mod:`fuzzynav.tuning.evaluate`,
:mod:`fuzzynav.tuning.export` and :mod:`fuzzynav.tuning.study_report`.
"""
from __future__ import annotations

from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.kinds import StudyKind, register_kind

__all__ = ["FuzzyPlan", "load"]


class FuzzyPlan:
    """A fuzzy study config opened with its simulation cache (see :mod:`fuzzynav.tuning.kinds`)."""

    kind = "fuzzy"

    def __init__(self, cfg, cache_dir=None):
        self.cfg = cfg
        self.cache_dir = cache_dir
        self.name = cfg.name
        self.path = cfg.path
        self.evaluator = None

    def parts(self) -> list:
        return [""]

    def config(self, key: str = ""):
        return self.cfg

    def first_trials(self) -> list:
        """Parameters to enqueue in a new study: with a warm start
        (:mod:`fuzzynav.tuning.warm_start`), the trial where each warm-started controller
        outputs its parent's constant; else none."""
        from fuzzynav.tuning.space import ControllerSpace
        from fuzzynav.tuning.warm_start import first_trial

        params = {}
        for cc in self.cfg.controllers:
            if cc.parent is not None:
                params.update(first_trial(ControllerSpace.from_config(cc)))
        return [params] if params else []

    def warm(self, processes: int = 1, progress: bool = True):
        """Compile the kernels if the cache is cold (saying so), then a warm evaluator made
        by ``processes`` processes (:func:`fuzzynav.tuning.prefetch.warm_shared`)."""
        from fuzzynav.tuning.prefetch import warm_shared
        from fuzzynav.tuning.warmup import warm_up

        if self.evaluator is None:
            warm_up(self.cfg, self.cache_dir, progress)  # a cold cache compiles: say so here
            self.evaluator = warm_shared(self.cfg, self.cache_dir, processes)
        return self.evaluator

    def objective(self, key: str, worker: int = 0):
        from fuzzynav.tuning.objective import Objective

        return Objective(self.cfg, self.cache_dir, worker, self.evaluator)

    def finish(self, studies: dict, storage=None) -> list:
        """Nothing to write (export writes rule files); the line ``study run`` prints."""
        return [f"study {self.name}: {len(studies[''].trials)} trials in "
                f"{storage or self.cfg.storage_url}"]

    def summary(self, studies: dict) -> None:
        """The best trial and its train/test table (printed)."""
        from fuzzynav.tuning.evaluate import format_scenarios, format_summary, run_table
        from fuzzynav.tuning.export import choose_trial, systems_of
        from fuzzynav.tuning.objective import CANDIDATE, Evaluator

        cfg, study = self.cfg, studies[""]
        try:
            trial = choose_trial(study, cfg)
        except FuzzynavError as exc:  # e.g. every trial so far failed or was pruned
            print(f"no summary: {exc}")
            return
        print(f"best trial {trial.number}: score "
              f"{trial.values if cfg.multi_objective else round(trial.value, 4)} "
              f"(ratios to {cfg.baseline}: "
              + ", ".join(f"{k} {v:.3f}"
                          for k, v in (trial.user_attrs.get('ratios') or {}).items())
              + ")")
        ev = Evaluator(cfg, self.cache_dir)
        systems = systems_of(cfg, trial)
        compare = tuple(f for f in dict.fromkeys(cfg.compare) if f != cfg.baseline)
        train = run_table(ev, systems, cfg.train, compare)
        test = run_table(ev, systems, cfg.test, compare)
        print("mean ratio of RMS error to the EKF (95 % CI over runs; < 1 beats the EKF):")
        print(format_summary(train, test))
        print("per scenario or recording (paired change of the score, + = smaller error):")
        print(format_scenarios(train, test, [CANDIDATE], cfg.baseline, markdown=False))

    def export(self, studies: dict, out, trial=None, pareto=None) -> list:
        from fuzzynav.tuning.export import export_rules

        return export_rules(self.cfg, studies[""], out, trial, pareto, self.cache_dir)

    def report(self, studies: dict, out, evaluate: bool = True):
        from fuzzynav.tuning.study_report import write_report

        return write_report(self.cfg, studies[""], out, self.cache_dir, evaluate=evaluate)


def load(path, cache_dir=None) -> FuzzyPlan:
    """Read and check a fuzzy study file (:func:`fuzzynav.tuning.study_config.load_study_config`)."""
    from fuzzynav.tuning.study_config import load_study_config

    return FuzzyPlan(load_study_config(Path(path)), cache_dir)


register_kind(StudyKind("fuzzy", lambda doc: "controllers" in doc, load,
                        "fuzzy controllers ([[controllers]]) scored against the baseline"))
