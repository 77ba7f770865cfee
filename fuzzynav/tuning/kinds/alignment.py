"""The alignment study: paper 002's ROR -> t rules of the fuzzy alignment filter, or the
constant multipliers of its classical counterpart.

A file with ``kind = "alignment"`` (or a top-level ``template``) is one Optuna study run by
the one driver; a trial is a candidate scored on the simulated alignment runs
(:class:`AlignmentObjective`).  With ``filter = "align-fuzzy"`` (the default) a candidate
is a rule set around ``template`` and :meth:`AlignmentPlan.finish` writes the tuned rule
file with its ``expected`` block; with ``filter = "align-kf-tuned"`` it is the constant R
and Q multipliers of :mod:`fuzzynav.align.tuned` (no template, no expected block) and
``output`` is a tuned-parameter file (``fuzzynav-baselines``) that
``align-kf-tuned@FILE`` reads -- the equally tuned classical filter, with the same
budget, sampler, objective and runs as the fuzzy study it is compared with.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.fileio import study_output
from fuzzynav.sim.tomltable import Table, read_toml, with_path
from fuzzynav.tuning.kinds import StudyKind, register_kind, study_settings
from fuzzynav.tuning.objective import TrialObjective

__all__ = ["FUZZY_FILTERS", "DEFAULT_SAMPLER", "AlignmentConfig", "load_alignment_config",
           "AlignmentObjective", "AlignmentPlan"]

#: the fuzzy alignment filters whose rules an alignment study tunes
FUZZY_FILTERS = ("align-fuzzy", "align-fuzzy-fast")
#: the sampler of an alignment study unless its file names one (Optuna's default TPE,
#: which the study used before it ran on the one driver)
DEFAULT_SAMPLER = "tpe-univariate"


@dataclass(frozen=True)
class AlignmentConfig:
    """A parsed alignment tuning file.

    Attributes
    ----------
    study : StudyConfig
        What the study driver reads: name (default: the file's stem), storage (default: a
        journal file next to it), sampler (default :data:`DEFAULT_SAMPLER`), seed
        (``sampler_seed``), trials (``n_trials``), ``stale_after_s``; the train and test
        runs; no pruner (a trial is scored on every training run).
    template, output : Path
        The hand rule file searched around (None for ``align-kf-tuned``), and where the
        tuned rule file (or tuned-parameter file) is written.
    template_doc : dict
        The template's JSON document (None for ``align-kf-tuned``).
    filter : str
        The alignment filter run (``align-fuzzy``, or ``align-kf-tuned``: then the study
        searches its constants, :data:`fuzzynav.align.tuned.SPACE`).
    azimuth_weight : float
    expected : tuple
        ``(scenario, seed)`` whose metrics the tuned rule file records (None for
        ``align-kf-tuned``).
    """

    study: object
    template: Path
    template_doc: dict
    output: Path
    filter: str
    azimuth_weight: float
    expected: tuple

    @property
    def constants(self) -> bool:
        """Whether the study searches constant multipliers (``align-kf-tuned``)."""
        from fuzzynav.align.tuned import NAME

        return self.filter == NAME


def _names(doc: dict, key: str, kind, path) -> list:
    value = doc.pop(key, [])
    if not isinstance(value, list) or not all(isinstance(v, kind) and not isinstance(v, bool)
                                              for v in value):
        raise InputFileError(str(path), key, f"must be an array of {kind.__name__}")
    return value


def load_alignment_config(path) -> AlignmentConfig:
    """Read and check an alignment tuning file (errors name the file and the key)."""
    from fuzzynav.align import tune, tuned
    from fuzzynav.tuning.samplers import get_optimiser, optimiser_names

    path = Path(path)
    doc = dict(read_toml(path, "alignment tuning file"))
    lists = {k: _names(doc, k, str if k in ("train", "test") else int, path)
             for k in ("train", "test", "train_seeds", "test_seeds")}
    t = Table(doc)
    here = path.parent
    with with_path(str(path)):
        if t.string("kind", "alignment") != "alignment":
            raise t.error("kind", "must be \"alignment\" in an alignment tuning file")
        sampler = t.string("sampler", DEFAULT_SAMPLER)
        if sampler not in optimiser_names():
            raise t.error("sampler", f"unknown sampler {sampler!r}; known: "
                                     f"{', '.join(sorted(optimiser_names()))}")
        why_not = get_optimiser(sampler).check(False)
        if why_not:
            raise t.error("sampler", why_not)
        filt = t.string("filter", "align-fuzzy", choices=(*FUZZY_FILTERS, tuned.NAME))
        constants = filt == tuned.NAME
        kinds = {True: "log", False: "linear"}
        space = ({k: (lo, hi, kinds[log]) for k, (lo, hi, log) in tuned.SPACE.items()}
                 if constants else tune.SPACE)
        study = study_settings(
            path, t.string("name", path.stem), sampler=sampler,
            seed=t.integer("sampler_seed", 0, lo=0),
            trials=t.integer("n_trials", 30, lo=1, hi=100000), storage=t.string("storage", ""),
            stale_after_s=t.number("stale_after_s", 300.0, lo=0.0, lo_open=True),
            train=((s, d) for s in lists["train"] for d in lists["train_seeds"]),
            test=((s, d) for s in lists["test"] for d in lists["test_seeds"]),
            space=((k, lo, hi, kind) for k, (lo, hi, kind) in space.items()),
            description=t.string("description", ""),
            baseline="align-kf" if constants else "paper rules", filter=filt)
        if not study.train:
            raise t.error("train", "the study needs at least one training run "
                                   "(train and train_seeds)")
        for key in ("template", "expected_scenario", "expected_seed"):
            if constants and t.has(key):
                raise t.error(key, f"not read by an {filt} study (it searches constant "
                                   "multipliers: no rule template, no expected block)")
        template = None if constants else (here / t.string("template")).resolve()
        acfg = AlignmentConfig(
            study=study, template=template,
            template_doc=None if constants else _read_template(template, path),
            output=study_output(t.string("output"), path, "output").resolve(),
            filter=study.filter, azimuth_weight=t.number("azimuth_weight", 1.0, lo=0.0),
            expected=None if constants else (t.string("expected_scenario"),
                                             t.integer("expected_seed", lo=0)))
        t.finish()
    return acfg


def _read_template(template: Path, path: Path) -> dict:
    try:
        return json.loads(template.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputFileError(str(path), "template",
                             f"cannot read {template} ({type(exc).__name__})") from None


class AlignmentObjective(TrialObjective):
    """Optuna objective of an alignment study: the mean over the training runs of
    ``align_time_s / duration_s + azimuth_weight * final_azimuth_arcmin / threshold``.

    Parameters
    ----------
    acfg : AlignmentConfig
    train : Runs
        The training runs, prepared (shared by forked workers).
    worker : int
    """

    def __init__(self, acfg, train, worker: int = 0):
        super().__init__(acfg.study, worker)
        self.acfg, self.train = acfg, train

    def _run(self, trial):
        from fuzzynav.align.tune import candidate, suggest
        from fuzzynav.fuzzy import load_fis

        self.claim(trial)
        acfg = self.acfg
        if acfg.constants:
            from fuzzynav.align.tuned import SPACE
            from fuzzynav.tuning.baseline_config import suggest as suggest_constants

            value = self.train.score(None, acfg.filter, acfg.azimuth_weight,
                                     suggest_constants(trial, SPACE))[0]
        else:
            fis = load_fis(candidate(acfg.template_doc, suggest(trial)))
            value = self.train.score(fis, acfg.filter, acfg.azimuth_weight)[0]
        trial.set_user_attr("n_runs", len(self.train.items))
        return value


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
        return AlignmentObjective(self.acfg, self.train, worker)

    def chosen(self, study, trial=None):
        """The best complete trial of ``study``, or trial number ``trial`` (complete)."""
        from fuzzynav.tuning.optuna_study import best_trials

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

    def summary_of(self, study, trial=None) -> tuple:
        """``(chosen trial, summary)``: the train and held-out objective of the best trial
        (or trial ``trial``) against the untuned filter, and its parameters."""
        from fuzzynav.align.tune import tuned_constants, tuned_rules
        from fuzzynav.tuning.optuna_study import n_finished

        chosen = self.chosen(study, trial)
        if self.acfg.constants:
            return chosen, tuned_constants(self.acfg, chosen.params, chosen.value, self.train)
        return chosen, tuned_rules(self.acfg, chosen.params, chosen.value, n_finished(study),
                                   self.train)[1]

    def _write(self, study, out, trial=None) -> tuple:
        from fuzzynav.align.tune import tuned_rules, write_json
        from fuzzynav.tuning.optuna_study import n_finished

        if self.acfg.constants:  # a tuned-parameter file, as a baseline study writes
            from fuzzynav.tuning.baseline_config import BaselineConfig, write_params

            chosen, summary = self.summary_of(study, trial)
            name = self.acfg.filter
            bcfg = BaselineConfig(self.acfg.study, (name,), Path(out))
            return write_params(bcfg, {name: dict(chosen.params)}, {name: chosen.value},
                                {name: n_finished(study)}), summary
        chosen = self.chosen(study, trial)
        doc, summary = tuned_rules(self.acfg, chosen.params, chosen.value, n_finished(study),
                                   self.train)
        return write_json(out, doc), summary

    def finish(self, studies: dict, storage=None) -> list:
        """Write the tuned rule file (or tuned-parameter file) of the best trial (the file's
        ``output``)."""
        path, self.last_summary = self._write(studies[""], self.acfg.output)
        return [json.dumps(self.last_summary, indent=2), f"wrote {path}"]

    def summary(self, studies: dict) -> None:
        """(Printed by :meth:`finish`: train and held-out scores against the paper's.)"""

    def export(self, studies: dict, out, trial=None, pareto=None) -> list:
        """Write the rule file (parameter file) of the best trial (or trial ``trial``) to
        ``out``."""
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
    return AlignmentPlan(load_alignment_config(path), cache_dir)


register_kind(StudyKind("alignment", _detect, _load,
                        "the fuzzy alignment filter's ROR -> t rules (kind = \"alignment\")"))
