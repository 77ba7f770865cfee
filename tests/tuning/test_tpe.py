"""``sampler = "tpe"``: Optuna's own multivariate group TPE over the conditional space.

The lazy group sampler that used Optuna internals (enabled only on Optuna 5.0) is gone;
these tests check what the registry now builds, on whatever Optuna is installed.
"""
from __future__ import annotations

import math
from unittest import mock

import optuna

from fuzzynav.tuning.samplers import get_optimiser
from fuzzynav.tuning.space import ControllerSpace, build_all
from tests.tuning.test_space import ATT, controller

optuna.logging.set_verbosity(optuna.logging.ERROR)
SPACES = [ControllerSpace.from_config(controller(window=(5, 40), output_range=(1.01, 1.5))),
          ControllerSpace.from_config(controller(template=ATT, name="att",
                                                 partitions={"dom_att": (3, 5)}))]


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


def proposals(seed: int, n: int = 25):
    study = optuna.create_study(sampler=get_optimiser("tpe").make(None, seed))
    study.optimize(toy_objective, n_trials=n)
    return [(t.params, t.state) for t in study.trials]


def test_tpe_is_optunas_multivariate_group_sampler():
    # the arguments it is built with (public), not Optuna's private attributes
    with mock.patch.object(optuna.samplers, "TPESampler",
                           wraps=optuna.samplers.TPESampler) as cls:
        sampler = get_optimiser("tpe").make(None, 5)
    assert isinstance(sampler, optuna.samplers.TPESampler)
    kw = cls.call_args.kwargs
    # what the space needs: one group per partition structure, liars for parallel workers
    assert kw["multivariate"] and kw["group"] and kw["constant_liar"] and kw["seed"] == 5


def test_a_seeded_study_proposes_the_same_trials_again():
    first, again = proposals(7), proposals(7)
    assert first == again
    assert proposals(8) != first  # the seed reaches the sampler
    # the structures differ between trials: the space is conditional, the test not trivial
    assert len({frozenset(p) for p, _ in first}) > 3
    assert any(s == optuna.trial.TrialState.PRUNED for _, s in first)
