"""The baseline study: classical filters tuned with a fuzzy study's budget (``[baselines]``).

One Optuna study per searched filter (``<name>.<filter>``, in the file's storage), each a
part of the plan run by the one driver; ALS is estimated, not searched
(:mod:`fuzzynav.tuning.als_fit`).  :meth:`BaselinePlan.finish` writes the tuned-parameter
file the named filters read (``ekf-tuned@FILE``; :mod:`fuzzynav.tuning.baseline_config`).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.kinds import StudyKind, register_kind

__all__ = ["BaselinePlan"]


class BaselinePlan:
    """A baseline study file opened with its simulation cache (see
    :mod:`fuzzynav.tuning.kinds`).  Every part shares one evaluator (logs and the
    baseline's metrics on the training runs)."""

    kind = "baselines"

    def __init__(self, bcfg, cache_dir=None):
        self.bcfg = bcfg
        self.cache_dir = cache_dir
        self.name = bcfg.study.name
        self.path = bcfg.study.path
        self._evaluator = None
        self._configs = {}

    @property
    def evaluator(self):
        """The shared :class:`~fuzzynav.tuning.objective.Evaluator` (made on first use)."""
        if self._evaluator is None:
            from fuzzynav.tuning.objective import Evaluator

            self._evaluator = Evaluator(self.bcfg.study, self.cache_dir)
        return self._evaluator

    def parts(self) -> list:
        """The searched filters (``als`` is estimated in :meth:`finish`)."""
        return [name for name in self.bcfg.tune if name != "als"]

    def space(self, key: str) -> dict:
        from fuzzynav.tuning.baseline_config import space_of, training_channels

        return space_of(key, training_channels(self.evaluator, self.bcfg.study.train),
                        self.bcfg.ranges.get(key))

    def config(self, key: str):
        """The study of filter ``key`` (:func:`fuzzynav.tuning.baseline_config.sub_config`)."""
        from fuzzynav.tuning.baseline_config import sub_config

        if key not in self.parts():
            raise FuzzynavError(f"{self.path}: [baselines] tune has no searched filter {key!r}")
        if key not in self._configs:
            self._configs[key] = sub_config(self.bcfg.study, key, self.space(key))
        return self._configs[key]

    def warm(self, processes: int = 1, progress: bool = True):
        """Load the training logs and run the baseline on each (``processes`` processes
        share those runs, :func:`fuzzynav.tuning.prefetch.prepare_shared`), saying so if
        the kernels compile."""
        from fuzzynav.tuning.prefetch import prepare_shared
        from fuzzynav.tuning.warmup import compiling

        with compiling(progress):
            prepare_shared(self.evaluator, list(self.bcfg.study.train), processes)
        return self.evaluator

    def objective(self, key: str, worker: int = 0):
        from fuzzynav.tuning.baseline_config import BaselineObjective

        return BaselineObjective(self.config(key), self.evaluator, key, self.space(key),
                                 worker)

    def finish(self, studies: dict, storage=None) -> list:
        """Write the parameter file (the config's ``[baselines] out``)."""
        return [f"wrote {self.write(studies)}"]

    def write(self, studies: dict, out=None) -> Path:
        """Estimate ALS (if listed), take every study's best trial and write the
        parameter file (``out``: elsewhere than the config's ``[baselines] out``)."""
        from fuzzynav.tuning.baseline_config import best_params, train_score, write_params
        from fuzzynav.tuning.pso import history as swarm_history

        bcfg = self.bcfg if out is None else replace(self.bcfg, out=Path(out))
        found, scores, counts, hist, spaces = {}, {}, {}, {}, {}
        for name in bcfg.tune:
            if name == "als":
                from fuzzynav.tuning.als_fit import als_params

                found[name] = als_params(self.evaluator, bcfg.study.train)
                if not found[name]:  # an empty entry would run as the plain EKF: 1.0
                    raise FuzzynavError("[baselines] tune = 'als': the training runs have no "
                                        "GNSS receiver, the only sensor ALS estimates R "
                                        "for; drop 'als' from tune")
                scores[name] = train_score(self.evaluator, name, found[name])
                counts[name] = 0
                continue
            study = studies[name]
            found[name], scores[name] = best_params(bcfg, study)
            counts[name] = len(study.get_trials(deepcopy=False))
            spaces[name] = self.space(name)
            if bcfg.study.sampler == "pso":
                hist[name] = swarm_history(study, self.config(name))
        return write_params(bcfg, found, scores, counts, hist, spaces)

    def summary(self, studies: dict) -> None:
        from fuzzynav.tuning.baseline_report import evaluate_baselines
        from fuzzynav.tuning.evaluate import format_scenarios, format_summary

        train, test = evaluate_baselines(self.bcfg, self.cache_dir)
        print(f"mean ratio of RMS error to {self.bcfg.study.baseline} (95 % CI over runs):")
        print(format_summary(train, test))
        print("per scenario or recording (paired change of the score, + = smaller error):")
        print(format_scenarios(train, test, list(self.bcfg.tune), self.bcfg.study.baseline,
                               markdown=False))

    def export(self, studies: dict, out, trial=None, pareto=None) -> list:
        """Write the parameter file of the studies' best trials to ``out``."""
        if trial is not None or pareto is not None:
            raise FuzzynavError("a baseline study exports every filter's best trial: "
                                "--trial and --pareto do not apply")
        return [self.write(studies, out)]

    def report(self, studies: dict, out, evaluate: bool = True):
        from fuzzynav.tuning.baseline_report import write_baseline_report

        return write_baseline_report(self.bcfg, out, self.cache_dir, evaluate)


def _load(path, cache_dir=None) -> BaselinePlan:
    from fuzzynav.tuning.baseline_config import load_baseline_config

    return BaselinePlan(load_baseline_config(path), cache_dir)


register_kind(StudyKind("baselines", lambda doc: "baselines" in doc, _load,
                        "classical filters tuned with the same budget ([baselines])"))
