"""A study whose first run is refused leaves nothing behind: no journal file it created, no
empty study in a storage it shares, and a study that existed before keeps its trials."""
from __future__ import annotations

import optuna
import pytest

from fuzzynav.cli import main
from fuzzynav.tuning.optuna_study import make_storage
from tests.tuning.studies import write_study

#: the tiny scenario simulates no magnetometer, so a weight on r_use is refused at the
#: first trial's score (tuning.objective.score_metrics)
REFUSED = {"weights": {"pos": 1.0, "vel": 1.0, "att": 1.0, "r_use": 0.1}}


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    _, err = capsys.readouterr()
    return code, err


def _names(journal) -> list:
    return optuna.get_all_study_names(make_storage(f"journal:{journal}", heartbeat=False))


@pytest.mark.parametrize("workers", [1, 2])
def test_a_refused_new_study_leaves_no_journal(capsys, tmp_path, sim_cache, workers):
    cfg = write_study(tmp_path, objective=REFUSED)
    code, err = run(capsys, "study", "run", cfg, "--trials", 2, "--workers", workers,
                    "--no-summary", "--cache", sim_cache)
    assert code == 2
    assert "'r_use' has weight 0.1" in err and "Traceback" not in err
    assert not (tmp_path / "tiny.journal").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.toml"]


def test_in_a_shared_journal_only_the_refused_study_goes(capsys, tmp_path, sim_cache):
    journal = tmp_path / "shared.journal"
    good = write_study(tmp_path)
    code, _ = run(capsys, "study", "run", good, "--trials", 2, "--no-summary",
                  "--storage", f"journal:{journal}", "--cache", sim_cache)
    assert code == 0 and _names(journal) == ["tiny"]
    bad = write_study(tmp_path, name="other", objective=REFUSED)
    code, err = run(capsys, "study", "run", bad, "--trials", 2, "--no-summary",
                    "--storage", f"journal:{journal}", "--cache", sim_cache)
    assert code == 2 and "'r_use' has weight" in err
    assert _names(journal) == ["tiny"]
    kept = optuna.load_study(study_name="tiny",
                             storage=make_storage(f"journal:{journal}", heartbeat=False))
    assert len(kept.trials) == 2


def test_a_study_that_existed_is_not_removed_when_a_resumed_run_is_refused(
        capsys, tmp_path, sim_cache):
    cfg = write_study(tmp_path)
    code, _ = run(capsys, "study", "run", cfg, "--trials", 2, "--no-summary",
                  "--cache", sim_cache)
    assert code == 0
    cfg = write_study(tmp_path, objective=REFUSED)  # the same study name, now refused
    code, _ = run(capsys, "study", "run", cfg, "--trials", 3, "--no-summary",
                  "--cache", sim_cache)
    assert code == 2
    journal = tmp_path / "tiny.journal"
    study = optuna.load_study(study_name="tiny",
                              storage=make_storage(f"journal:{journal}", heartbeat=False))
    assert sum(t.state == optuna.trial.TrialState.COMPLETE for t in study.trials) == 2


def test_a_refused_study_in_a_new_sqlite_file_leaves_no_file(capsys, tmp_path, sim_cache):
    cfg = write_study(tmp_path, objective=REFUSED)
    db = tmp_path / "studies.db"
    code, err = run(capsys, "study", "run", cfg, "--trials", 2, "--no-summary",
                    "--storage", f"sqlite:///{db}", "--cache", sim_cache)
    assert code == 2 and "'r_use' has weight" in err
    assert not db.exists()


def test_interrupted_before_the_first_trial_the_new_study_goes(tmp_path, sim_cache,
                                                               monkeypatch):
    from fuzzynav.tuning.kinds.fuzzy import FuzzyPlan
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.study_run import run_study

    def interrupted(self, processes=1, progress=True):
        raise KeyboardInterrupt  # Ctrl-C while the training runs are simulated

    monkeypatch.setattr(FuzzyPlan, "warm", interrupted)
    cfg = load_study_config(write_study(tmp_path))
    with pytest.raises(KeyboardInterrupt):
        run_study(cfg, trials=2, cache_dir=sim_cache, progress=False)
    assert not (tmp_path / "tiny.journal").exists()
