"""Tune the ROR -> t controller of the fuzzy alignment filter with Optuna (a small driver).

``python -m fuzzynav.align.tune studies/align/paper002_tune.toml`` runs the study (TPE,
in memory), prints train and held-out scores of the tuned controller against the paper's
hand rules, and writes the tuned rule file with its provenance and an ``expected`` block
(``kind = "alignment"``: one scenario and seed, its metrics) that
``tests/align/test_tuned_rules.py`` re-runs.

The search space keeps the paper's three rules and changes only numbers: the centre of
t's ``less1`` in [0.5, 0.99] and of ``more1`` in [1.01, 2.0] (``equal1`` stays at 1 so that a
consistent filter keeps R), where ``more1`` starts to rise on the ROR axis ([1.0, 2.0]) and
reaches 1 (+[0.2, 2.0]), and the window M in [3, 30] epochs.
"""
from __future__ import annotations

import copy
import datetime
import json
import sys
from pathlib import Path

import numpy as np

from fuzzynav import __version__
from fuzzynav.align import run as R
from fuzzynav.align.experiment import metrics
from fuzzynav.align.fuzzy_r import FuzzyRScaling
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.fileio import publish, study_output
from fuzzynav.fuzzy import load_fis
from fuzzynav.errors import InputFileError
from fuzzynav.sim.tomltable import Table, read_toml, with_path


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


class Runs:
    """Simulated logs and epochs of (scenario, seed), prepared once."""

    def __init__(self, pairs):
        self.items = []
        for name, seed in pairs:
            scn = load_alignment_scenario(name)
            log = R.simulate(scn, seed)
            self.items.append((name, seed, scn, log, R.epochs(scn, log, seed)))

    def score(self, fis, filt, weight) -> tuple[float, list]:
        """Mean objective and the per-run metrics."""
        vals, rows = [], []
        for name, seed, scn, log, ep in self.items:
            out = R.run_align_filter(filt, scn, log, ep, rules=fis)
            m = metrics(out, scn.threshold_arcmin)
            vals.append(m["align_time_s"] / scn.duration_s
                        + weight * m["final_azimuth_arcmin"] / scn.threshold_arcmin)
            rows.append({"scenario": name, "seed": seed, **m})
        return float(np.mean(vals)), rows


def _names(doc: dict, key: str, kind, path) -> list:
    value = doc.pop(key, [])
    if not isinstance(value, list) or not all(isinstance(v, kind) and not isinstance(v, bool)
                                              for v in value):
        raise InputFileError(str(path), key, f"must be an array of {kind.__name__}")
    return value


def _config(path: Path) -> dict:
    doc = read_toml(path, "alignment tuning file")
    lists = {k: _names(doc, k, str if k in ("train", "test") else int, path)
             for k in ("train", "test", "train_seeds", "test_seeds")}
    t = Table(doc)
    here = path.parent
    cfg = {"template": (here / t.string("template")).resolve(),
           "output": study_output(t.string("output"), path, "output").resolve(),
           "filter": t.string("filter", "align-fuzzy"),
           "n_trials": t.integer("n_trials", 30, lo=1, hi=100000),
           "sampler_seed": t.integer("sampler_seed", 0, lo=0),
           "azimuth_weight": t.number("azimuth_weight", 1.0, lo=0.0),
           "train": [(s, d) for s in lists["train"] for d in lists["train_seeds"]],
           "test": [(s, d) for s in lists["test"] for d in lists["test_seeds"]],
           "expected": (t.string("expected_scenario"), t.integer("expected_seed", lo=0))}
    with with_path(str(path)):
        t.finish()
    return cfg


def tune(path) -> dict:
    """Run the study of a tuning file; write the tuned rule file; return a summary."""
    import optuna

    path = Path(path)
    cfg = _config(path)
    template = json.loads(cfg["template"].read_text(encoding="utf-8"))
    train = Runs(cfg["train"])
    filt, w = cfg["filter"], cfg["azimuth_weight"]

    def objective(trial):
        p = {"t_less": trial.suggest_float("t_less", 0.5, 0.99),
             "t_more": trial.suggest_float("t_more", 1.01, 2.0),
             "more_start": trial.suggest_float("more_start", 1.0, 2.0),
             "more_rise": trial.suggest_float("more_rise", 0.2, 2.0),
             "window": trial.suggest_int("window", 3, 30)}
        return train.score(load_fis(candidate(template, p)), filt, w)[0]

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(sampler=optuna.samplers.TPESampler(seed=cfg["sampler_seed"]))
    study.optimize(objective, n_trials=cfg["n_trials"])
    doc = candidate(template, study.best_params)
    test = Runs(cfg["test"])
    summary = {"train": {"paper": train.score(load_fis(template), filt, w)[0],
                         "tuned": study.best_value},
               "test": ({"paper": test.score(load_fis(template), filt, w)[0],
                         "tuned": test.score(load_fis(doc), filt, w)[0]} if test.items else {}),
               "best_params": study.best_params}
    exp = Runs([cfg["expected"]])
    _, rows = exp.score(load_fis(doc), filt, w)
    doc["name"] = "paper002-ror-tuned"
    doc["provenance"] = {"source": "fuzzynav.align.tune", "config": str(path),
                         "template": str(cfg["template"].name), "filter": filt,
                         "trials": cfg["n_trials"], "objective": summary,
                         "train": cfg["train"], "test": cfg["test"],
                         "package_version": __version__,
                         "created": datetime.datetime.now(datetime.timezone.utc).isoformat(
                             timespec="seconds")}
    doc["expected"] = {"kind": "alignment", "scenario": cfg["expected"][0],
                       "seed": cfg["expected"][1], "filter": filt,
                       "metrics": {k: v for k, v in rows[0].items()
                                   if k not in ("scenario", "seed")}}
    _write_json(cfg["output"], doc)
    return summary


def _write_json(path: Path, doc: dict) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    publish(tmp, path)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    print(json.dumps(tune(argv[0]), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
