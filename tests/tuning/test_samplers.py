"""The optimiser registry (a new optimiser is a sampler plus an entry), the journal's fsync
policy and the heartbeat's rate."""
from __future__ import annotations

import optuna
import pytest
from optuna.distributions import CategoricalDistribution
from optuna.trial import TrialState

from fuzzynav.errors import UnknownNameError
from fuzzynav.tuning import journal
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.objective import Objective
from fuzzynav.tuning.study_run import run_study
from fuzzynav.tuning.samplers import OPTIMISERS, Optimiser, get_optimiser, register_optimiser
from fuzzynav.tuning.optuna_study import make_pruner
from tests.tuning.studies import write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


class LowestCorner(optuna.samplers.BaseSampler):
    """Every parameter at its lower bound (categorical: the first choice)."""

    def infer_relative_search_space(self, study, trial):
        return {}

    def sample_relative(self, study, trial, search_space):
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        d = param_distribution
        return d.choices[0] if isinstance(d, CategoricalDistribution) else d.low


@pytest.fixture
def corner():
    register_optimiser(Optimiser("test-corner", lambda cfg, seed: LowestCorner(),
                                 "lowest corner", pruning=False))
    yield
    del OPTIMISERS["test-corner"]


def test_a_new_optimiser_is_a_sampler_and_a_registry_entry(tmp_path, sim_cache, corner):
    cfg = load_study_config(write_study(tmp_path, study={"sampler": "test-corner",
                                                         "pruner": "median", "trials": 2}))
    assert isinstance(make_pruner(cfg), optuna.pruners.NopPruner)  # its entry says so
    study = run_study(cfg, cache_dir=sim_cache, progress=False)
    assert [t.state for t in study.trials] == [TrialState.COMPLETE] * 2
    for t in study.trials:
        for name, d in t.distributions.items():
            low = d.choices[0] if isinstance(d, CategoricalDistribution) else d.low
            assert t.params[name] == low, name
        assert t.user_attrs["n_runs"] == len(cfg.train)


def test_the_registry_names_what_an_optimiser_cannot_do():
    assert get_optimiser("pso").check(multi_objective=True) == "pso is single-objective here"
    assert get_optimiser("nsga2").check(multi_objective=True) is None
    needy = Optimiser("needy", None, needs="no_such_package_here")
    assert "needs the no_such_package_here package" in needy.check(False)
    with pytest.raises(UnknownNameError, match="pso"):  # lists the known names
        get_optimiser("pos")


def test_the_journal_syncs_only_records_that_change_state(tmp_path, monkeypatch):
    synced = []
    monkeypatch.setattr(journal.os, "fsync", lambda fd: synced.append(fd))
    storage = journal.open_journal(str(tmp_path / "j.journal"))
    study = optuna.create_study(storage=storage)
    counts = [len(synced)]
    trial = study.ask()
    counts.append(len(synced))
    trial.suggest_float("x", 0.0, 1.0)
    trial.report(0.5, step=0)
    trial.set_user_attr("heartbeat", 1.0)
    counts.append(len(synced))
    study.tell(trial, 0.25)
    counts.append(len(synced))
    assert counts == [1, 2, 2, 3]  # create study, create trial, (lazy records), finish
    again = optuna.load_study(study_name=study.study_name,  # every record is in the file
                              storage=journal.open_journal(str(tmp_path / "j.journal")))
    t = again.trials[0]
    assert (t.params, t.intermediate_values, t.user_attrs, t.value) == \
        ({"x": trial.params["x"]}, {0: 0.5}, {"heartbeat": 1.0}, 0.25)


class Recorder:
    def __init__(self):
        self.attrs = []

    def set_user_attr(self, key, value):
        self.attrs.append(key)


def test_the_heartbeat_is_written_at_most_every_few_seconds(tmp_path, monkeypatch):
    cfg = load_study_config(write_study(tmp_path, study={"stale_after_s": 30.0}))
    obj = Objective(cfg)
    assert obj._beat_every_s == 3.0  # a tenth of stale_after_s, at most 10 s
    now = [1000.0]
    monkeypatch.setattr("fuzzynav.tuning.objective.time.time", lambda: now[0])
    rec = Recorder()
    obj._beat(rec, force=True)
    for dt in (0.5, 1.0, 2.9):
        now[0] = 1000.0 + dt
        obj._beat(rec)
    assert rec.attrs == ["heartbeat"]
    now[0] = 1003.0
    obj._beat(rec)
    assert rec.attrs == ["heartbeat"] * 2
