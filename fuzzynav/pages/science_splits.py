"""Recordings split into a training and a held-out part, every filter tuned on the same part.

Part of the "Held-out recordings" section of ``docs/science.md``
(:mod:`fuzzynav.pages.science_recordings`).  A :class:`Split` names a fuzzy study trained on
part of a recording (``studies/rtklib_split.toml``: the car drive's first half;
``studies/paper004_fuzzy.toml`` / ``_rev``: four A-KIT trajectories), the rule file exported
from it, and the parameter file of the classical filters tuned with the same budget, training
runs, objective and pruner (``studies/rtklib_split_baselines.toml``,
``studies/paper004_baselines.toml`` / ``_rev``).  Every filter runs on the study's held-out
runs; the score is the studies' objective (mean of the 3-D position and velocity RMS ratios)
taken against ``ekf-tuned`` of the same split, and the fuzzy controller is paired against the
best classical filter of the table (:func:`fuzzynav.pages.scores.best_classical`: chosen on
the held-out runs themselves, which favours the classical side).

The pairs are what the held-out part offers: noise seeds of the one held-out half of the car
drive (the noise added to its fixes), or the held-out A-KIT trajectories (four per fold).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd

from fuzzynav.pages.common import REPO_ROOT as ROOT
from fuzzynav.report import diff_cell

__all__ = ["SPLIT_METRICS", "UNTUNED", "Split", "CAR_SPLIT", "AKIT_FOLDS", "split_specs",
           "pair_ids", "held_out_runs", "split_frame", "comparison", "score_table", "splits_lines",
           "missing_note"]

#: the studies' objective (weights pos 1, vel 1; recordings score no attitude)
SPLIT_METRICS = ("rms_pos_m", "rms_vel_mps")
#: untuned classical filters run beside the tuned ones (their defaults: zero budget)
UNTUNED = ("ekf", "sage-husa", "vb", "huber")


@dataclass(frozen=True)
class Split:
    """One recording split: what was tuned on its training part, and with what.

    Attributes
    ----------
    label : str
        The held-out set's name in the tables.
    fuzzy : str
        Label of the fuzzy controller tuned on the training part.
    study : str
        The fuzzy study file (its ``[test]`` recordings are the held-out runs).
    rules : str
        The rule file exported from it.
    params : str
        The classical filters tuned on the same training part (a baseline study's file).
    apso : str or None
        Paper 004's APSO multipliers tuned on the same part (another budget), if any.
    supervisors : tuple
        ``(label, named filter, rule file)`` of further fuzzy designs tuned on the same part
        (the fuzzy supervisors, warm-started at their tuned parents).
    """

    label: str
    fuzzy: str
    study: str
    rules: str
    params: str
    apso: str | None = None
    supervisors: tuple = ()

    def files(self) -> list:
        """The files it needs (the supervisors' are optional: :meth:`available`)."""
        return [self.study, self.rules, self.params] + ([self.apso] if self.apso else [])

    def available(self, root: Path = ROOT) -> "Split":
        """This split with only the supervisors whose rule file exists under ``root``."""
        return replace(self, supervisors=tuple(s for s in self.supervisors
                                               if (root / s[2]).is_file()))

    def designs(self) -> list:
        """The labels of its fuzzy designs, the R-scaling controller first."""
        return [self.fuzzy, *(label for label, _, _ in self.supervisors)]

    def missing(self, root: Path = ROOT) -> list:
        """The files of this split that are absent under ``root``."""
        return [f for f in self.files() if not (root / f).is_file()]


CAR_SPLIT = Split("rtklib-drive@50-100%", "fuzzy-drive", "studies/rtklib_split.toml",
                  "rules/rtklib_drive_tuned.json", "studies/rtklib_split_baselines.json",
                  supervisors=tuple(
                      (f"fuzzy-{n}-tuned", f"fuzzy-{n}",
                       f"rules/rtklib_drive_supervisor_{n.replace('-', '_')}_tuned.json")
                      for n in ("sage-husa", "vb", "huber")))
AKIT_FOLDS = (
    Split("akit 1-4 → 5-8", "fuzzy-auv", "studies/paper004_fuzzy.toml",
          "rules/paper004_fuzzy_dvl.json", "studies/paper004_baselines.json",
          "studies/paper004_apso.json"),
    Split("akit 5-8 → 1-4", "fuzzy-auv", "studies/paper004_fuzzy_rev.toml",
          "rules/paper004_fuzzy_dvl_rev.json", "studies/paper004_baselines_rev.json",
          "studies/paper004_apso_rev.json"),
)


def split_specs(split: Split, tuned, root: Path = ROOT, untuned=UNTUNED) -> dict:
    """Table label -> filter spec of every filter judged on ``split`` (``tuned``: the names
    in its parameter file)."""
    specs = {split.fuzzy: f"fakf@{root / split.rules}"}
    specs.update({label: f"{name}@{root / rules}" for label, name, rules in split.supervisors})
    specs.update({name: f"{name}@{root / split.params}" for name in tuned})
    specs.update({name: name for name in untuned if name not in specs})
    if split.apso:
        specs["apso"] = f"apso@{root / split.apso}"
    return specs


def pair_ids(runs) -> list:
    """The pair of each held-out run: its seed on one recording (noise seeds), the session
    on several (trajectories).

    Raises
    ------
    ValueError
        Several sessions *and* several seeds (no one pairing), or a session that is not a
        number.
    """
    from fuzzynav.realdata.dataspec import parse_recording_spec

    sessions = [parse_recording_spec(name).session for name, _ in runs]
    if len(set(sessions)) <= 1:
        return [int(seed) for _, seed in runs]
    if len({seed for _, seed in runs}) > 1:
        raise ValueError(f"held-out runs over several sessions and seeds: {sorted(runs)}")
    return [int(s) for s in sessions]


def held_out_runs(cfg, seeds=None) -> list:
    """The recorded ``[test]`` runs of a study (``seeds``: replace the seeds of a run on a
    single recording, e.g. more noise seeds of the car drive's held-out half)."""
    from fuzzynav.realdata.dataspec import is_recording_name

    runs = [r for r in cfg.test if is_recording_name(r[0])]
    names = list(dict.fromkeys(n for n, _ in runs))
    if seeds is not None and len(names) == 1:
        runs = [(names[0], int(s)) for s in seeds]
    return runs


def split_frame(split: Split, cache=None, seeds=None, root: Path = ROOT,
                untuned=UNTUNED) -> pd.DataFrame:
    """One row per (held-out run, filter): metrics; ``scenario`` is the split's label and
    ``seed`` the pair (:func:`pair_ids`), ``run`` the run's own name (``untuned``: the
    untuned filters run beside the split's own)."""
    import json

    from fuzzynav.tuning.evaluate import run_table
    from fuzzynav.tuning.objective import Evaluator
    from fuzzynav.tuning.study_config import load_study_config

    cfg = load_study_config(root / split.study)
    runs = held_out_runs(cfg, seeds)
    tuned = list(json.loads((root / split.params).read_text())["filters"])
    specs = split_specs(split, tuned, root, untuned)
    df = run_table(Evaluator(cfg, cache), {}, runs, tuple(specs.values()))
    df = df.replace({"filter": {v: k for k, v in specs.items()}})
    pairs = dict(zip(runs, pair_ids(runs)))
    return df.assign(run=df["scenario"], scenario=split.label,
                     seed=[pairs[(n, s)] for n, s in zip(df["scenario"], df["seed"])])


def comparison(scores: pd.DataFrame, splits, unit: str) -> tuple:
    """Table rows and sentences: each split's fuzzy controller against the best classical
    filter of its held-out set and against ``ekf-tuned`` (paired, 95 % CI over ``unit``)."""
    from fuzzynav.pages import scores as sr

    rows = ["| held-out set | fuzzy | best classical | fuzzy − best (95 % CI) | verdict | "
            "fuzzy − ekf-tuned (95 % CI) | verdict |", "|---|---|---|---|---|---|---|"]
    text = []
    for sp in splits:
        best = sr.best_classical(scores, sp.label)
        for fuzzy in sp.designs():
            vs_best = sr.paired(scores, sp.label, fuzzy, best)
            vs_ref = sr.paired(scores, sp.label, fuzzy, sr.REF)
            rows.append(f"| `{sp.label}` | `{fuzzy}` | {best} | {diff_cell(vs_best)} | "
                        f"{sr.verdict(vs_best)} | {diff_cell(vs_ref)} | {sr.verdict(vs_ref)} |")
            text.append("- " + sr.sentence(sp.label, f"`{fuzzy}`", f"`{best}`", vs_best,
                                           unit))
    return rows, text


def score_table(scores: pd.DataFrame, splits) -> list:
    """Filter x held-out set: mean score (95 % CI over the pairs), fuzzy first."""
    from fuzzynav.pages import scores as sr

    labels = [sp.label for sp in splits]
    names = list(dict.fromkeys([*(d for sp in splits for d in sp.designs()),
                                *scores[scores["scenario"].isin(labels)]["filter"]]))
    return sr.ratio_table(scores, names, labels)


def splits_lines(splits, frames: dict, unit: str, what: str) -> list:
    """The markdown of some splits (``frames``: label -> :func:`split_frame`)."""
    from fuzzynav.pages import scores as sr

    df = pd.concat(frames.values(), ignore_index=True)
    scores = sr.scores_to(df, sr.REF, SPLIT_METRICS)
    rows, text = comparison(scores, splits, unit)
    return [f"Score: the studies' objective (mean of the 3-D position and velocity RMS "
            f"ratios) against `{sr.REF}` tuned on the same training part; mean (95 % CI over "
            f"{what}). `-tuned` filters and the fuzzy controller were tuned with the same "
            "budget, training runs, objective and pruner; the untuned filters run with their "
            "defaults. The best classical filter is chosen on the held-out runs themselves "
            "(which favours it).", "", *score_table(scores, splits), "", *rows, "", *text, ""]


def missing_note(splits, root: Path = ROOT) -> list:
    """A sentence per split whose files are absent (empty when all are there)."""
    out = []
    for sp in splits:
        gone = sp.missing(root)
        if gone:
            out.append(f"*`{sp.label}` is not judged: {', '.join(f'`{g}`' for g in gone)} "
                       "absent (run the studies named in docs/science.md).*")
        for label, _, rules in sp.supervisors:
            if not gone and not (root / rules).is_file():
                out.append(f"*`{label}` is not judged on `{sp.label}`: `{rules}` absent.*")
    return out
