"""python -m fuzzynav.pages.fairctl: the richer controller against the tuned baselines.

Its held-out table and report had fallen behind the science page's refactoring (it called
functions that no longer exist): run here end to end on a tiny study, the tuning replaced
by the template's own rules."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from fuzzynav.fuzzy import load_fis
from fuzzynav.pages import fairctl
from fuzzynav.pages import scores as sc
from fuzzynav.tuning.study_config import load_study_config
from tests.tuning.studies import GPS, write_study

COMPARE = ["ekf", "ekf-tuned", "sage-husa", "sage-husa-tuned", "ekf-true"]


@pytest.fixture
def tiny(tmp_path):
    cfg = load_study_config(write_study(tmp_path, test={"scenarios": [str(fairctl.ROOT / "tests"
                                                                      / "tuning" / "data"
                                                                      / "tiny.toml")],
                                                        "seeds": [100, 101, 102],
                                                        "compare": COMPARE}))
    return cfg, {"gps": load_fis(GPS)}


def test_the_held_out_table_has_the_controller_and_every_compared_filter(tiny, sim_cache):
    cfg, systems = tiny
    df = fairctl.held_out_table(cfg, systems, fairctl.PARAMS, sim_cache)
    assert set(df["filter"]) == {sc.FUZZY, *COMPARE}
    assert len(df) == 3 * (1 + len(COMPARE))  # every filter on the three held-out runs
    assert df["rms_pos_m"].gt(0).all()


def test_main_prints_the_comparison_and_the_verdict(tiny, sim_cache, tmp_path, monkeypatch,
                                                    capsys):
    cfg, systems = tiny
    trial = SimpleNamespace(number=0, value=0.9, params={})
    monkeypatch.setattr(fairctl, "tune", lambda *a: (cfg, systems, trial))
    assert fairctl.main(["--work", str(tmp_path / "w"), "--cache", str(sim_cache)]) == 0
    out = capsys.readouterr().out
    assert "| scenario | best classical |" in out
    assert f"`{sc.FUZZY}` wins " in out and "of 1 held-out sets" in out
    assert (tmp_path / "w" / "fair_ctl_runs.csv").is_file()
