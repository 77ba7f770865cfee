"""The alignment study: paper 002's ROR -> t rules of the fuzzy alignment filter.

A file with ``kind = "alignment"`` (or a top-level ``template``; :mod:`fuzzynav.align.tune`)
is one Optuna study run by the one driver; a trial is a candidate rule set scored on the
simulated alignment runs (:class:`fuzzynav.align.tune.AlignmentObjective`).
:meth:`AlignmentPlan.finish` writes the tuned rule file with its ``expected`` block.
"""
from __future__ import annotations

from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.kinds import StudyKind, register_kind


class AlignmentPlan:
    """An alignment tuning file opened (see :mod:`fuzzynav.tuning.kinds`); the simulated
    training runs are prepared once and shared by forked workers."""

    kind = "alignment"

    def __init__(self, acfg, cache_dir=None):
        self.acfg = acfg
        self.cache_dir = cache_dir  # (alignment runs are simulated in memory)
        self.name = acfg.study.name
        self.path = acfg.study.path
        self._train = None

    def parts(self) -> list:
        return [""]

    def config(self, key: str = ""):
        return self.acfg.study

    @property
    def train(self):
        """The training runs (:class:`fuzzynav.align.tune.Runs`, simulated on first use)."""
        if self._train is None:
            from fuzzynav.align.tune import Runs

            self._train = Runs(self.acfg.study.train)
        return self._train

    def warm(self, processes: int = 1, progress: bool = True):
        """Simulate the training runs (once; forked workers inherit them)."""
        return self.train

    def objective(self, key: str, worker: int = 0):
        from fuzzynav.align.tune import AlignmentObjective

        return AlignmentObjective(self.acfg, self.train, worker)

    def _chosen(self, study, trial=None):
        from fuzzynav.tuning.study import best_trials

        full = best_trials(study, self.acfg.study)
        if trial is None:
            if not full:
                raise FuzzynavError(f"study {self.name!r}: no finished trial yet")
            return full[0]
        found = [t for t in full if t.number == trial]
        if not found:
            raise FuzzynavError(f"study {self.name!r}: trial {trial} is not a complete "
                                f"trial (complete: {sorted(t.number for t in full)})")
        return found[0]

    def _write(self, study, out, trial=None) -> tuple:
        from fuzzynav.align.tune import tuned_rules, write_json
        from fuzzynav.tuning.study import n_finished

        chosen = self._chosen(study, trial)
        doc, summary = tuned_rules(self.acfg, chosen.params, chosen.value, n_finished(study),
                                   self.train)
        return write_json(out, doc), summary

    def finish(self, studies: dict, storage=None) -> list:
        """Write the tuned rule file of the best trial (the file's ``output``)."""
        import json

        path, self.last_summary = self._write(studies[""], self.acfg.output)
        return [json.dumps(self.last_summary, indent=2), f"wrote {path}"]

    def summary(self, studies: dict) -> None:
        """(Printed by :meth:`finish`: train and held-out scores against the paper's.)"""

    def export(self, studies: dict, out, trial=None, pareto=None) -> list:
        """Write the rule file of the best trial (or trial ``trial``) to ``out``."""
        if pareto is not None:
            raise FuzzynavError("an alignment study has one objective: --pareto does not apply")
        return [self._write(studies[""], Path(out), trial)[0]]

    def report(self, studies: dict, out, evaluate: bool = True):
        """``trials.csv`` and ``report.md`` (best trial; with ``evaluate``, its train and
        held-out scores against the paper's rules), staged: all or nothing."""
        from fuzzynav.tuning.kinds.alignment_report import write_alignment_report

        return write_alignment_report(self, studies[""], out, evaluate)


def _detect(doc: dict) -> bool:
    return doc.get("kind") == "alignment" or "template" in doc


def _load(path, cache_dir=None) -> AlignmentPlan:
    from fuzzynav.align.tune import load_alignment_config

    return AlignmentPlan(load_alignment_config(path), cache_dir)


register_kind(StudyKind("alignment", _detect, _load,
                        "the fuzzy alignment filter's ROR -> t rules (kind = \"alignment\")"))
