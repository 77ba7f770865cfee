"""Baseline and alignment studies on the one study driver: ``fuzzynav study run --workers 2``
runs their trials in worker processes that claim them (slot lock: exactly the total), a
resumed run continues the same study, and a trial left ``RUNNING`` by a dead worker is
reaped (failed, its parameters retried) -- as for fuzzy studies."""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time

import optuna
import pytest
from optuna.trial import TrialState

from fuzzynav.cli import main
from fuzzynav.errors import InputFileError
from fuzzynav.filters.baselines import read_params
from fuzzynav.tuning.kinds import kind_of, load_plan
from fuzzynav.tuning.optuna_study import open_study
from tests.tuning.studies import ROOT, RULES, TINY

optuna.logging.set_verbosity(optuna.logging.ERROR)

BASELINE = f"""
name = "bl"
[study]
sampler = "random"
seed = 0
trials = 2
pruner = "none"
[train]
scenarios = ["{TINY}"]
seeds = [0, 1]
[test]
scenarios = ["{TINY}"]
seeds = [100]
compare = ["ekf"]
[baselines]
tune = ["huber-tuned"]
out = "tuned.json"
"""

SHORT = """kind = "alignment"
base = "paper002-rmismatch"
name = "short"
duration_s = 80.0
[imu]
rate_hz = 10.0
"""


def _alignment_study(tmp_path, **extra):
    scn = tmp_path / "short.toml"
    scn.write_text(SHORT)
    lines = "".join(f"{k} = {json.dumps(v)}\n" for k, v in extra.items())
    cfg = tmp_path / "al.toml"
    cfg.write_text(f'''kind = "alignment"
template = "{RULES / 'paper002_ror.json'}"
output = "tuned.json"
n_trials = 2
train = ["{scn}"]
train_seeds = [0, 1]
test = []
expected_scenario = "{scn}"
expected_seed = 3
{lines}''')
    return cfg


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _orphan(study, suggest):
    """A trial left RUNNING by a worker of this host that died (its pid is gone)."""
    t = study.ask()
    suggest(t)
    for k, v in (("host", socket.gethostname()), ("pid", _dead_pid()), ("worker", 0),
                 ("heartbeat", time.time())):
        t.set_user_attr(k, v)
    return t.number


def _check_worker_trials(trials, n):
    done = [t for t in trials if t.state == TrialState.COMPLETE]
    assert len(done) == n  # the slot lock: exactly the total, no trial more
    for t in done:  # every trial claimed by a worker process, not run in this one
        assert t.user_attrs["host"] == socket.gethostname()
        assert t.user_attrs["pid"] != os.getpid() and t.user_attrs["worker"] in (0, 1)
        assert "heartbeat" in t.user_attrs
    return done


def _huber(trial):
    trial.suggest_float("gamma", 0.5, 10.0, log=True)


def test_baseline_study_runs_with_two_workers_resumes_and_reaps(capsys, tmp_path, sim_cache):
    cfg = tmp_path / "bl.toml"
    cfg.write_text(BASELINE)
    assert kind_of(cfg).name == "baselines"
    _run(capsys, "study", "run", cfg, "--workers", 2, "--no-summary", "--cache", sim_cache)
    plan = load_plan(cfg, sim_cache)
    part = plan.config("huber-tuned")
    study = open_study(part)
    first = _check_worker_trials(study.get_trials(), 2)
    before = {t.number: (t.params, t.value) for t in first}
    orphan = _orphan(study, _huber)

    out = _run(capsys, "study", "run", cfg, "--workers", 2, "--trials", 4, "--no-summary",
               "--cache", sim_cache)
    assert f"wrote {tmp_path / 'tuned.json'}" in out
    trials = open_study(part).get_trials()
    done = _check_worker_trials(trials, 4)
    assert {t.number: (t.params, t.value) for t in done if t.number in before} == before
    assert trials[orphan].state == TrialState.FAIL  # reaped on resume, its params retried
    retry = [t for t in trials if t.user_attrs.get("retry_of") == orphan]
    assert len(retry) == 1 and retry[0].params == trials[orphan].params
    doc = json.loads((tmp_path / "tuned.json").read_text())
    best = min(done, key=lambda t: t.value)
    assert doc["filters"]["huber-tuned"] == best.params and doc["trials"]["huber-tuned"] == 5
    assert read_params(tmp_path / "tuned.json")["filters"] == doc["filters"]  # it reads back

    # export (elsewhere) and report read the same studies
    out = _run(capsys, "study", "export", cfg, "--out", tmp_path / "again.json",
               "--cache", sim_cache)
    assert out.strip() == f"wrote {tmp_path / 'again.json'}"
    assert json.loads((tmp_path / "again.json").read_text())["filters"] == doc["filters"]
    out = _run(capsys, "study", "report", cfg, "--no-eval", "--cache", sim_cache)
    assert "huber-tuned" in (tmp_path / "bl_report" / "report.md").read_text()

    # a worker started as a new interpreter (where workers are not forked) finds its part
    from fuzzynav.tuning.worker import main as worker_main

    assert worker_main([str(cfg), "--total", "5", "--part", "huber-tuned",
                        "--cache", str(sim_cache)]) == 0
    assert len(open_study(part).get_trials(states=(TrialState.COMPLETE,))) == 5


def test_alignment_study_runs_with_two_workers_resumes_and_reaps(capsys, tmp_path):
    from fuzzynav.align.tune import suggest

    cfg = _alignment_study(tmp_path)
    assert kind_of(cfg).name == "alignment"
    out = _run(capsys, "study", "run", cfg, "--workers", 2, "--no-summary")
    assert f"wrote {tmp_path / 'tuned.json'}" in out
    part = load_plan(cfg).config("")
    study = open_study(part)
    before = {t.number: (t.params, t.value) for t in _check_worker_trials(study.get_trials(), 2)}
    orphan = _orphan(study, suggest)

    _run(capsys, "study", "run", cfg, "--workers", 2, "--trials", 4, "--no-summary")
    trials = open_study(part).get_trials()
    done = _check_worker_trials(trials, 4)
    assert {t.number: (t.params, t.value) for t in done if t.number in before} == before
    assert trials[orphan].state == TrialState.FAIL
    assert [t.params for t in trials if t.user_attrs.get("retry_of") == orphan] == \
        [trials[orphan].params]
    doc = json.loads((tmp_path / "tuned.json").read_text())
    best = min(done, key=lambda t: t.value)
    assert doc["binding"]["window"] == best.params["window"]
    assert doc["provenance"]["trials"] == 4 and doc["provenance"]["objective"]["train"][
        "tuned"] == best.value

    # export of a chosen trial, and the report
    other = next(t for t in done if t.number != best.number)
    out = _run(capsys, "study", "export", cfg, "--out", tmp_path / "t.json",
               "--trial", other.number)
    assert json.loads((tmp_path / "t.json").read_text())["binding"]["window"] == \
        other.params["window"]
    out = _run(capsys, "study", "report", cfg, "--no-eval")
    report = tmp_path / "al_report" / "report.md"
    assert f"wrote {report}" in out and f"Best trial {best.number}" in report.read_text()
    assert len((tmp_path / "al_report" / "trials.csv").read_text().splitlines()) == 1 + 5


def test_an_alignment_file_with_a_bad_sampler_names_file_and_key(tmp_path):
    cfg = _alignment_study(tmp_path, sampler="nsga2-typo")
    with pytest.raises(InputFileError, match=r"al\.toml: sampler: unknown sampler 'nsga2-typo'"):
        load_plan(cfg)
    cfg = _alignment_study(tmp_path, n_trials_typo=3)
    with pytest.raises(InputFileError, match=r"al\.toml.*n_trials_typo"):
        load_plan(cfg)


def test_the_shipped_alignment_study_is_one_the_driver_runs():
    plan = load_plan(ROOT / "studies" / "align" / "paper002_tune.toml")
    cfg = plan.config("")
    assert plan.kind == "alignment" and cfg.trials == 30 and cfg.seed == 2
    assert plan.acfg.output.parent == ROOT / "studies" / "align"  # a study writes only there
    assert len(cfg.train) == 4 and len(cfg.test) == 9


def test_the_removed_entry_points_are_gone():
    for mod in ("fuzzynav/tuning/apso.py",):
        assert not (ROOT / mod).exists()
    from fuzzynav.align import tune

    assert not hasattr(tune, "main") and not hasattr(tune, "tune")
