"""The lazy group TPE sampler proposes exactly what Optuna's TPESampler proposes.

Each comparison runs the same seeded study twice, once with Optuna's own sampler
(``tpe.ENABLED = False``, the reference) and once with :class:`LazyGroupTPESampler`.
"""
from __future__ import annotations

import math

import optuna
import pytest
from optuna.search_space.group_decomposed import _GroupDecomposedSearchSpace

from fuzzynav.tuning import tpe
from fuzzynav.tuning.config import load_study_config
from fuzzynav.tuning.run import run_study
from fuzzynav.tuning.samplers import get_optimiser
from fuzzynav.tuning.space import ControllerSpace, build_all
from tests.tuning.studies import write_study
from tests.tuning.test_space import ATT, controller

optuna.logging.set_verbosity(optuna.logging.ERROR)
SPACES = [ControllerSpace.from_config(controller(window=(5, 40), output_range=(1.01, 1.5))),
          ControllerSpace.from_config(controller(template=ATT, name="att",
                                                 partitions={"dom_att": (3, 5)}))]

#: the lazy sampler is checked against the Optuna releases it was written for; on another
#: release it is not used (the last test checks that) and these comparisons do not apply
checked_optuna = pytest.mark.skipif(not tpe.SUPPORTED, reason=(
    f"Optuna {optuna.__version__} is not in tpe.CHECKED_OPTUNA: sampler 'tpe' is Optuna's own"))


def toy_objective(trial):
    """Both controllers' conditional spaces; a value from the parameters, some trials
    pruned (so pruned trials feed the sampler too)."""
    build_all(SPACES, trial)
    value = sum(math.sin(float(v) * (i + 1)) for i, v in enumerate(trial.params.values())
                if not isinstance(v, str))
    if trial.number % 7 == 3:
        trial.report(value, step=0)
        raise optuna.TrialPruned()
    return value


def proposals(monkeypatch, enabled: bool, n: int = 30):
    monkeypatch.setattr(tpe, "ENABLED", enabled)
    study = optuna.create_study(sampler=get_optimiser("tpe").make(None, 7))
    study.optimize(toy_objective, n_trials=n)
    return [(t.params, t.state, t.value) for t in study.trials]


@checked_optuna
def test_lazy_sampler_proposes_optunas_parameters(monkeypatch):
    eager, lazy = proposals(monkeypatch, False), proposals(monkeypatch, True)
    assert isinstance(get_optimiser("tpe").make(None, 0), tpe.LazyGroupTPESampler)
    # (identical parameters: the same random numbers through the same code)
    assert [p for p, _, _ in lazy] == [p for p, _, _ in eager]
    assert [s for _, s, _ in lazy] == [s for _, s, _ in eager]
    # the structures differ between trials: the space is conditional, the test not trivial
    assert len({frozenset(p) for p, _, _ in eager}) > 3


@checked_optuna
def test_sampling_only_the_groups_a_trial_uses_skips_most(monkeypatch):
    calls = []
    sample = tpe.LazyGroupTPESampler._sample_group
    monkeypatch.setattr(tpe.LazyGroupTPESampler, "_sample_group",
                        lambda self, *a: calls.append(1) or sample(self, *a))
    monkeypatch.setattr(tpe, "ENABLED", True)
    study = optuna.create_study(sampler=get_optimiser("tpe").make(None, 7))
    study.optimize(toy_objective, n_trials=20)
    groups = len(study.sampler._search_space_group.search_spaces)
    assert 0 < len(calls) < 10 * groups  # 10 TPE trials (after 10 random), each fewer groups


def _groups(space):
    return [sorted(g) for g in space.search_spaces]


@checked_optuna
def test_incremental_search_space_matches_optunas_also_out_of_order():
    study = optuna.create_study()
    inc, full = tpe.IncrementalGroupSearchSpace(True), _GroupDecomposedSearchSpace(True)
    trials = [study.ask() for _ in range(6)]
    names = [("a", "b"), ("a", "c"), ("a", "b", "d"), ("e",), ("a", "c", "e"), ("b", "f")]
    for t, keys in zip(trials, names):
        for k in keys:
            t.suggest_float(k, 0.0, 1.0)
    for i in (0, 1, 4, 2, 5, 3):  # out of number order, as with two workers
        study.tell(trials[i], 0.5)
        assert _groups(inc.calculate(study)) == _groups(full.calculate(study))
    assert len(inc.calculate(study).search_spaces) > 3


@checked_optuna
@pytest.mark.slow
def test_seeded_study_reaches_the_same_values(tmp_path, sim_cache, monkeypatch):
    """A 1-worker paper-000 study (tiny flight, TPE, Wilcoxon pruning) with both samplers."""
    runs = []
    for enabled in (False, True):
        monkeypatch.setattr(tpe, "ENABLED", enabled)
        (tmp_path / str(enabled)).mkdir()
        cfg = load_study_config(write_study(tmp_path / str(enabled), name="tiny",
                                            study={"sampler": "tpe", "pruner": "wilcoxon"}))
        study = run_study(cfg, trials=14, cache_dir=sim_cache, progress=False)
        runs.append([(t.params, t.state, t.value) for t in study.trials])
    (eager, lazy) = runs
    assert [p for p, _, _ in lazy] == [p for p, _, _ in eager]
    assert [s for _, s, _ in lazy] == [s for _, s, _ in eager]
    # the same filter runs on the same parameters: values agree to rounding
    assert all(math.isclose(a, b, rel_tol=1e-12) for (_, _, a), (_, _, b) in zip(lazy, eager))


def test_the_lazy_sampler_is_the_default_only_on_a_checked_optuna():
    checked = ".".join(optuna.__version__.split(".")[:2]) in tpe.CHECKED_OPTUNA
    assert tpe.SUPPORTED == checked
    sampler = get_optimiser("tpe").make(None, 0)
    assert isinstance(sampler, tpe.LazyGroupTPESampler) == checked
    assert isinstance(sampler, optuna.samplers.TPESampler)
