"""fuzzynav's Wilcoxon pruner decides as Optuna's does, without copying the best trial."""
import numpy as np
import optuna
import pytest
from optuna.distributions import FloatDistribution
from optuna.trial import TrialState, create_trial

from fuzzynav.tuning import optuna_patch_pruners
from fuzzynav.tuning.optuna_patch_pruners import WilcoxonPruner


def _study(rng):
    study = optuna.create_study(storage=optuna.storages.InMemoryStorage())
    for _ in range(4):
        steps = rng.uniform(0.5, 1.5, 9)
        study.add_trial(create_trial(value=float(steps.mean()), params={"a": 0.5},
                                     distributions={"a": FloatDistribution(0, 1)},
                                     intermediate_values=dict(enumerate(steps))))
    return study


def _without_private_best(monkeypatch):
    """As on the Optuna of pyproject's lower bound (4.2): no private uncopied best trial."""
    monkeypatch.setattr(optuna_patch_pruners, "PRIVATE_BEST_TRIAL", "_no_such_method")


@pytest.mark.parametrize("optuna_kind", [None, _without_private_best],
                         ids=["installed", "no-private-method"])
def test_same_decisions_as_optunas_pruner(optuna_kind, monkeypatch):
    copies = []
    if optuna_kind is not None:
        optuna_kind(monkeypatch)
        public = optuna.study.Study.best_trial
        monkeypatch.setattr(optuna.study.Study, "best_trial", property(
            lambda self: (copies.append("copied"), public.fget(self))[1]))
    rng = np.random.default_rng(3)
    study = _study(rng)
    ours = WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)
    theirs = optuna.pruners.WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)
    decisions = []
    for shift in np.linspace(-0.6, 1.2, 19):
        for n in (1, 3, 5, 9):
            vals = rng.uniform(0.5, 1.5, n) + shift
            trial = create_trial(state=TrialState.RUNNING, params={"a": 0.5},
                                 distributions={"a": FloatDistribution(0, 1)},
                                 intermediate_values=dict(enumerate(vals)))
            before = len(copies)
            d = ours.prune(study, trial)
            if optuna_kind is not None and n > 2:  # the fallback read the public property
                assert len(copies) == before + 1
            assert d == theirs.prune(study, trial)
            decisions.append(d)
    assert any(decisions) and not all(decisions)  # both kinds of decision were compared


@pytest.mark.skipif(not hasattr(optuna.study.Study, "_get_best_trial"),
                    reason="this Optuna has no private uncopied best trial (fallback tested above)")
def test_the_best_trial_is_not_copied(monkeypatch):
    study = _study(np.random.default_rng(0))
    monkeypatch.setattr(optuna.study.Study, "best_trial",
                        property(lambda self: (_ for _ in ()).throw(AssertionError("copied"))))
    trial = create_trial(state=TrialState.RUNNING, params={"a": 0.5},
                         distributions={"a": FloatDistribution(0, 1)},
                         intermediate_values=dict.fromkeys(range(6), 9.0))
    # six steps all far worse than the best trial's: one-sided p = 1/64 < 0.1
    assert WilcoxonPruner(p_threshold=0.1, n_startup_steps=2).prune(study, trial)
