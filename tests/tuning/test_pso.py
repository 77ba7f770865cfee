"""PSO over the rule space: the swarm's dynamics and inertia schedule, one trial per particle
and iteration, parameters inside their bounds, resuming (also mid-iteration) replays it."""
from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

import numpy as np
import optuna
import pytest
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning import pso
from fuzzynav.tuning import optuna_study as study_mod
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
from fuzzynav.tuning.space import build_all
from fuzzynav.tuning.optuna_study import Objective, open_study, reap_stale
from tests.tuning.studies import write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


def pso_config(tmp_path, name="swarm", **pso_kw):
    kw = dict(particles=4, iterations=3, inertia=[0.9, 0.4], c1=1.5, c2=1.5)
    kw.update(pso_kw)
    return load_study_config(write_study(
        tmp_path, name=name, study={"sampler": "pso", "seed": 7, "trials": 100, "pso": kw},
        file_name=f"{name}.toml"))


def unit(trial, name) -> float:
    """A float parameter as its coordinate in [0, 1]."""
    d = trial.distributions[name]
    return (trial.params[name] - d.low) / (d.high - d.low)


@pytest.fixture
def bowl(monkeypatch):
    """A cheap objective instead of the filter runs: squared distance of the float
    coordinates to 0.3 (the swarm's structure and bookkeeping stay the real ones)."""
    def run(self, trial):
        build_all(self.spaces, trial)
        floats = [k for k, d in trial.distributions.items()
                  if isinstance(d, optuna.distributions.FloatDistribution)]
        return float(sum((unit(trial, k) - 0.3) ** 2 for k in floats))

    monkeypatch.setattr(Objective, "_run", run)


def by_iteration(study):
    out = {}
    for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        out.setdefault(t.user_attrs["pso_iteration"], {})[t.user_attrs["particle"]] = t
    return out


def test_the_inertia_schedule_is_linear_from_start_to_end(tmp_path):
    cfg = pso_config(tmp_path, iterations=6, inertia=[0.9, 0.4])
    np.testing.assert_allclose([pso.inertia(cfg, k) for k in range(6)],
                               np.linspace(0.9, 0.4, 6), rtol=0, atol=1e-15)


def test_one_inertia_number_is_a_constant_weight(tmp_path):
    cfg = pso_config(tmp_path, iterations=6, inertia=0.7)
    assert cfg.pso.inertia == (0.7, 0.7)
    assert [pso.inertia(cfg, k) for k in range(6)] == [0.7] * 6


@pytest.mark.parametrize("inertia, w", [([0.95, 0.55], np.linspace(0.95, 0.55, 6)),
                                        (0.7, np.full(6, 0.7))])
def test_without_attraction_each_step_is_the_last_one_times_the_inertia(tmp_path, bowl,
                                                                        inertia, w):
    """c1 = c2 = 0: v_k+1 = w_k v_k, so the displacements of every coordinate that was not
    clipped at 0 or 1 shrink by exactly the scheduled weights -- the configured schedule
    over 6 iterations, also when --trials stops the run after 5; or the constant weight."""
    cfg = pso_config(tmp_path, particles=5, iterations=6, inertia=inertia, c1=0.0, c2=0.0)
    study = run_study(cfg, trials=25, progress=False)
    its = by_iteration(study)
    floats = [k for k, d in its[0][0].distributions.items()
              if isinstance(d, optuna.distributions.FloatDistribution)]
    ratios = {k: [] for k in range(1, 4)}
    for i in range(5):
        for name in floats:
            u = np.array([unit(its[k][i], name) for k in range(5)])
            if np.all((u > 0) & (u < 1)):
                d = np.diff(u)
                for k in range(1, 4):
                    ratios[k].append(d[k] / d[k - 1])
    for k in range(1, 4):
        assert len(ratios[k]) > 10
        np.testing.assert_allclose(ratios[k], w[k], rtol=1e-6)


def test_a_swarm_improves_on_a_bowl_and_contracts(tmp_path, bowl):
    cfg = pso_config(tmp_path, particles=8, iterations=8)
    its = by_iteration(run_study(cfg, progress=False))
    best = [min(t.value for t in its[k].values()) for k in range(8)]
    so_far = np.minimum.accumulate(best)
    assert so_far[-1] < 0.6 * so_far[0]
    spread = [np.mean([t.value for t in its[k].values()]) for k in (0, 7)]
    assert spread[1] < spread[0]  # the swarm gathers where the bowl is low


def test_a_study_holds_one_trial_per_particle_and_iteration(tmp_path, sim_cache):
    """With the real objective (filter runs) and parameters inside their bounds."""
    cfg = pso_config(tmp_path, particles=3, iterations=2)
    study = run_study(cfg, cache_dir=sim_cache, progress=False)
    trials = study.get_trials(deepcopy=False)
    assert [t.state for t in trials] == [TrialState.COMPLETE] * 6
    assert sorted((t.user_attrs["pso_iteration"], t.user_attrs["particle"]) for t in trials) \
        == [(k, i) for k in range(2) for i in range(3)]
    for t in trials:
        assert t.user_attrs["n_runs"] == len(cfg.train)
        for name, value in t.params.items():
            assert t.distributions[name]._contains(
                t.distributions[name].to_internal_repr(value)), (name, value)
    # the structure is fixed: the template's counts where allowed, else the smallest
    assert {t.params.get("gps.n.dom_pos") for t in trials} == {3}
    assert {t.params.get("gps.n.alpha") for t in trials} == {4}
    # a shorter --trials runs whole swarms of the same schedule
    short = pso_config(tmp_path, name="short", particles=3, iterations=2)
    assert len(run_study(short, trials=4, cache_dir=sim_cache, progress=False).trials) == 3


def test_corners_of_the_unit_cube_map_inside_every_parameter_range(tmp_path):
    cfg = pso_config(tmp_path)
    params, fixed = pso.structure(cfg)
    for u in (0.0, 1.0, np.nextafter(1.0, 0.0)):
        p = pso.to_params(np.full(len(params), u), params, fixed)
        for name, kind, spec in params:
            if kind == "cat":
                assert p[name] in spec
            else:
                assert spec[0] <= p[name] <= spec[1], (name, p[name], spec)


def test_resuming_reproduces_the_swarm(tmp_path, bowl):
    whole = run_study(pso_config(tmp_path, name="whole"), progress=False)
    part = pso_config(tmp_path, name="part")
    run_study(part, trials=8, progress=False)  # two of three swarms
    resumed = run_study(part, trials=12, progress=False)
    assert [t.params for t in resumed.trials] == [t.params for t in whole.trials]
    assert [t.value for t in resumed.trials] == [t.value for t in whole.trials]


def test_resuming_an_interrupted_swarm_finishes_it_without_repeating(tmp_path, bowl):
    whole = run_study(pso_config(tmp_path, name="whole"), progress=False)
    cfg = pso_config(tmp_path, name="cut")
    open_study(cfg, create=True)
    study_mod.run_worker(cfg, 5)  # the first swarm and one particle of the second, then stop
    assert [t.state for t in open_study(cfg).trials] == [TrialState.COMPLETE] * 5
    resumed = run_study(cfg, progress=False)
    assert [t.state for t in resumed.trials] == [TrialState.COMPLETE] * 12
    assert sorted((key(t), t.params, t.value) for t in resumed.trials) == \
        sorted((key(t), t.params, t.value) for t in whole.trials)


def key(t):
    """A trial's place in the swarm."""
    return t.user_attrs[pso.ITERATION], t.user_attrs[pso.PARTICLE]


def test_two_workers_evaluate_the_same_swarm_as_one(tmp_path, bowl, monkeypatch):
    """Two workers (threads here, each with its own storage handle and slot lock) share the
    swarm: every iteration waits for the previous one, so the particles, their parameters and
    values are those of one worker, though the trials interleave."""
    real = Objective._run

    def slow(self, trial):  # uneven durations, so the workers overtake each other
        time.sleep(0.01 * (trial.number % 3))
        return real(self, trial)

    monkeypatch.setattr(Objective, "_run", slow)
    one = run_study(pso_config(tmp_path, name="one"), progress=False)
    cfg = pso_config(tmp_path, name="two")
    open_study(cfg, create=True)
    ran = {}
    threads = [threading.Thread(target=lambda w: ran.update({w: study_mod.run_worker(
        cfg, 12, None, w)}), args=(w,)) for w in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    two = open_study(cfg).trials
    assert sum(ran.values()) == 12 and min(ran.values()) > 0  # both workers took particles
    assert [t.state for t in two] == [TrialState.COMPLETE] * 12
    assert sorted((key(t), t.params, t.value) for t in two) == \
        sorted((key(t), t.params, t.value) for t in one.trials)


def test_an_iteration_starts_only_when_the_one_before_has_every_value():
    def trial(it, i, state=TrialState.COMPLETE):
        return SimpleNamespace(user_attrs={pso.ITERATION: it, pso.PARTICLE: i}, state=state)

    done = [trial(0, i) for i in range(3)]
    assert pso.next_slot(pso.slots(done), 3) == ((1, 0), True)
    assert pso.next_slot(pso.slots(done[:2]), 3) == ((0, 2), True)
    running = done[:2] + [trial(0, 2, TrialState.RUNNING)]
    assert pso.next_slot(pso.slots(running), 3) == ((1, 0), False)
    failed = done[:2] + [trial(0, 2, TrialState.FAIL)]  # failed for good: counts as inf
    assert pso.next_slot(pso.slots(failed), 3) == ((1, 0), True)
    retried = failed + [trial(0, 2, TrialState.WAITING)]
    assert pso.next_slot(pso.slots(retried), 3) == ((1, 0), False)


def test_resuming_with_another_swarm_config_is_refused(tmp_path, bowl):
    run_study(pso_config(tmp_path, name="s"), trials=8, progress=False)
    changed = pso_config(tmp_path, name="s", c2=0.5)  # same study, other dynamics
    with pytest.raises(FuzzynavError, match="PSO iteration 1, particle 0 .* other parameters"):
        run_study(changed, trials=12, progress=False)


def test_a_retried_particle_keeps_its_place_in_the_swarm(tmp_path):
    cfg = pso_config(tmp_path)
    study = open_study(cfg, create=True)
    study.enqueue_trial({}, user_attrs={"pso_iteration": 2, "particle": 1})
    t = study.ask()
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    t.set_user_attr("host", socket.gethostname())
    t.set_user_attr("pid", p.pid)
    t.set_user_attr("heartbeat", time.time())
    t.suggest_float("gps.out_hi", 1.01, 1.3)
    assert reap_stale(study, 300.0) == 1
    retry = study.trials[-1]
    assert retry.state == TrialState.WAITING
    assert retry.user_attrs == {"pso_iteration": 2, "particle": 1, "retry_of": t.number,
                                "retries": 1}
