"""Tuning the ROR -> t controller of the fuzzy alignment filter: the alignment study kind.

The alignment-side pieces of the alignment study (its search space, the candidate rule
document, the scored runs, the tuned rule file); the study file, its objective and its runs
are :mod:`fuzzynav.tuning.kinds.alignment`.  ``fuzzynav study run
studies/align/paper002_tune.toml`` runs the study with the one study driver (workers,
journal or PostgreSQL storage, reaping, resume), prints train and held-out scores of the tuned controller against the
paper's hand rules, and writes the tuned rule file with its provenance and an ``expected``
block (``kind = "alignment"``: one scenario and seed, its metrics) that
``tests/align/test_tuned_rules.py`` re-runs.  ``fuzzynav study export`` writes the rule file
of the best (or a chosen) trial elsewhere, ``fuzzynav study report`` a trials table.

The same file with ``filter = "align-kf-tuned"`` tunes the classical counterpart instead:
a trial is the constant multipliers of :mod:`fuzzynav.align.tuned` (its ``SPACE``), scored
by the same :func:`objective` on the same runs, and the study writes a tuned-parameter file
(:func:`tuned_constants` is its summary against the untuned ``align-kf``).

The search space keeps the paper's three rules and changes only numbers: the centre of
t's ``less1`` in [0.5, 0.99] and of ``more1`` in [1.01, 2.0] (``equal1`` stays at 1 so that a
consistent filter keeps R), where ``more1`` starts to rise on the ROR axis ([1.0, 2.0]) and
reaches 1 (+[0.2, 2.0]), and the window M in [3, 30] epochs.
"""
from __future__ import annotations

import copy
import datetime
import json
from pathlib import Path

import numpy as np

from fuzzynav import __version__
from fuzzynav.align import alignment_run as R
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.fileio import publish
from fuzzynav.fuzzy import load_fis

__all__ = ["SPACE", "candidate", "suggest", "objective", "Runs", "tuned_rules",
           "tuned_constants", "write_json"]

#: the searched numbers: key -> (low, high, kind), in the order they are drawn
SPACE = {"t_less": (0.5, 0.99, "linear"), "t_more": (1.01, 2.0, "linear"),
         "more_start": (1.0, 2.0, "linear"), "more_rise": (0.2, 2.0, "linear"),
         "window": (3, 30, "int")}


def candidate(template: dict, p: dict) -> dict:
    """The template rule document with the numbers of ``p``."""
    doc = copy.deepcopy(template)
    ror = {t["name"]: t for t in doc["inputs"][0]["terms"]}
    out = {t["name"]: t for t in doc["outputs"][0]["terms"]}
    a, b = p["more_start"], p["more_start"] + p["more_rise"]
    ror["equal1"]["params"] = [0.0, 1.0, b]
    ror["more1"]["params"] = [a, b, max(b + 1.0, 4.0), max(b + 2.0, 5.0)]
    lo, hi = p["t_less"], p["t_more"]
    out["less1"]["params"] = [2 * lo - 1.0, lo, 1.0]
    out["equal1"]["params"] = [lo, 1.0, hi]
    out["more1"]["params"] = [1.0, hi, 2 * hi - 1.0]
    doc["outputs"][0]["range"] = [2 * lo - 1.0, 2 * hi - 1.0]
    doc["inputs"][0]["range"] = [0.0, max(b + 1.0, 3.0)]
    doc["binding"]["window"] = int(p["window"])
    return doc


def suggest(trial) -> dict:
    """Draw one candidate's numbers from an Optuna trial (:data:`SPACE`)."""
    return {k: (trial.suggest_int(k, lo, hi) if kind == "int" else
                trial.suggest_float(k, lo, hi)) for k, (lo, hi, kind) in SPACE.items()}


def objective(m: dict, scn, weight: float) -> float:
    """The alignment study's objective of one run's metrics ``m`` on scenario ``scn``:
    ``align_time_s / duration_s + weight * final_azimuth_arcmin / threshold_arcmin``."""
    return (m["align_time_s"] / scn.duration_s
            + weight * m["final_azimuth_arcmin"] / scn.threshold_arcmin)


class Runs:
    """Simulated logs and epochs of (scenario, seed), prepared once."""

    def __init__(self, pairs):
        self.items = []
        for name, seed in pairs:
            scn = load_alignment_scenario(name)
            log = R.simulate(scn, seed)
            self.items.append((name, seed, scn, log, R.epochs(scn, log, seed)))

    def score(self, fis, filt, weight, params=None) -> tuple[float, list]:
        """Mean objective and the per-run metrics of filter ``filt`` with the rules ``fis``
        (fuzzy filters) or the multipliers ``params`` (``align-kf-tuned``)."""
        vals, rows = [], []
        for name, seed, scn, log, ep in self.items:
            out = R.run_align_filter(filt, scn, log, ep, rules=fis, params=params)
            m = R.metrics(out, scn.threshold_arcmin)
            vals.append(objective(m, scn, weight))
            rows.append({"scenario": name, "seed": seed, **m})
        return float(np.mean(vals)), rows


def tuned_rules(acfg, params: dict, value: float, trials: int,
                train: Runs | None = None) -> tuple:
    """``(rule document, summary)`` of the candidate ``params`` (its training score
    ``value``, found in a study of ``trials`` trials): train and held-out scores against the
    paper's rules, provenance and the ``expected`` block."""
    filt, w = acfg.filter, acfg.azimuth_weight
    paper = load_fis(acfg.template_doc)
    train = train if train is not None else Runs(acfg.study.train)
    doc = candidate(acfg.template_doc, params)
    test = Runs(acfg.study.test)
    summary = {"train": {"paper": train.score(paper, filt, w)[0], "tuned": value},
               "test": ({"paper": test.score(paper, filt, w)[0],
                         "tuned": test.score(load_fis(doc), filt, w)[0]} if test.items else {}),
               "best_params": dict(params)}
    _, rows = Runs([acfg.expected]).score(load_fis(doc), filt, w)
    doc["name"] = "paper002-ror-tuned"
    doc["provenance"] = {"source": "fuzzynav study run", "config": str(acfg.study.path),
                         "template": str(acfg.template.name), "filter": filt,
                         "trials": trials, "objective": summary,
                         "train": [list(r) for r in acfg.study.train],
                         "test": [list(r) for r in acfg.study.test],
                         "package_version": __version__,
                         "created": datetime.datetime.now(datetime.timezone.utc).isoformat(
                             timespec="seconds")}
    doc["expected"] = {"kind": "alignment", "scenario": acfg.expected[0],
                       "seed": acfg.expected[1], "filter": filt,
                       "metrics": {k: v for k, v in rows[0].items()
                                   if k not in ("scenario", "seed")}}
    return doc, summary


def tuned_constants(acfg, params: dict, value: float, train: Runs | None = None) -> dict:
    """The summary of ``align-kf-tuned`` with the multipliers ``params`` (training score
    ``value``): train and held-out objective against the untuned ``align-kf``."""
    filt, w = acfg.filter, acfg.azimuth_weight
    train = train if train is not None else Runs(acfg.study.train)
    test = Runs(acfg.study.test)
    plain = acfg.study.baseline
    return {"train": {plain: train.score(None, plain, w)[0], "tuned": value},
            "test": ({plain: test.score(None, plain, w)[0],
                      "tuned": test.score(None, filt, w, params)[0]} if test.items else {}),
            "best_params": dict(params)}


def write_json(path: Path, doc: dict) -> Path:
    """Write ``doc`` to ``path`` through a temporary file (never half-written)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    publish(tmp, path)
    return path
