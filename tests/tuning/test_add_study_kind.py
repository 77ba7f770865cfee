"""Worked example: a new study kind is one plan class and one ``register_kind`` call.

The toy kind below tunes one number ``x`` to minimise ``(x - target)^2``.  Registered, its
files run through ``fuzzynav study run`` like the built-in kinds, with worker processes
that claim their trials (the trust features live in the driver and in
:class:`~fuzzynav.tuning.objective.TrialObjective`, not in the kind), resume and export.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from optuna.trial import TrialState

from fuzzynav.cli import main
from fuzzynav.sim.tomltable import Table, read_toml, with_path
from fuzzynav.tuning.kinds import KINDS, StudyKind, register_kind, study_settings
from fuzzynav.tuning.objective import TrialObjective
from fuzzynav.tuning.optuna_study import best_trials, open_study


class ToyObjective(TrialObjective):
    def __init__(self, cfg, target, worker):
        super().__init__(cfg, worker)
        self.target = target

    def _run(self, trial):
        self.claim(trial)                      # names this worker as the trial's owner
        x = trial.suggest_float("x", -5.0, 5.0)
        trial.set_user_attr("n_runs", len(self.cfg.train))  # a complete trial
        return (x - self.target) ** 2


class ToyPlan:
    kind = "toy"

    def __init__(self, path, cache_dir=None):
        with with_path(str(path)):
            t = Table(dict(read_toml(path, "toy study")))
            t.string("kind")
            self.target = t.number("target")
            self.cfg = study_settings(path, path.stem, sampler="random",
                                      seed=t.integer("seed", 0), trials=t.integer("trials"),
                                      train=(("toy", 0),))
            t.finish()
        self.name, self.path, self.cache_dir = self.cfg.name, self.cfg.path, cache_dir

    def parts(self):
        return [""]

    def config(self, key=""):
        return self.cfg

    def warm(self, processes=1, progress=True):
        pass  # nothing to load before the workers fork

    def objective(self, key, worker=0):
        return ToyObjective(self.cfg, self.target, worker)

    def _best(self, studies):
        return best_trials(studies[""], self.cfg)[0]

    def finish(self, studies, storage=None):
        return [f"best x = {self._best(studies).params['x']:.6f}"]

    def summary(self, studies):
        pass

    def export(self, studies, out, trial=None, pareto=None):
        Path(out).write_text(json.dumps(self._best(studies).params))
        return [out]

    def report(self, studies, out, evaluate=True):
        raise NotImplementedError


@pytest.fixture
def toy_kind():
    register_kind(StudyKind("toy", lambda doc: doc.get("kind") == "toy", ToyPlan))
    yield
    KINDS.pop("toy")


def test_a_registered_kind_runs_on_the_one_driver(toy_kind, tmp_path, capsys):
    cfg = tmp_path / "toy.toml"
    cfg.write_text('kind = "toy"\ntarget = 1.5\ntrials = 6\n')
    assert main(["study", "run", str(cfg), "--workers", "2"]) == 0
    assert main(["study", "run", str(cfg), "--trials", "8"]) == 0  # resumed
    out = capsys.readouterr().out
    trials = open_study(ToyPlan(cfg).cfg).get_trials()
    assert [t.state for t in trials] == [TrialState.COMPLETE] * 8
    assert {t.user_attrs["pid"] for t in trials[:6]} & {os.getpid()} == set()  # workers
    assert {t.user_attrs["pid"] for t in trials[6:]} == {os.getpid()}         # in-process
    best = min(trials, key=lambda t: t.value)
    assert best.value == pytest.approx((best.params["x"] - 1.5) ** 2)
    assert f"best x = {best.params['x']:.6f}" in out
    assert main(["study", "export", str(cfg), "--out", str(tmp_path / "x.json")]) == 0
    assert json.loads((tmp_path / "x.json").read_text()) == best.params
