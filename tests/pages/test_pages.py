"""The docs results pages: the registry against docs/, the CLI, the one mean ± CI cell."""
import dataclasses
import importlib
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from fuzzynav.cli import main
from fuzzynav.pages.common import markers, replace_section, stopped_early
from fuzzynav.pages.page_registry import PAGES
from fuzzynav.metrics import Estimate, mean_ci
from fuzzynav.report import ci_cell, diff_cell, improvement_cell, pooled_rows

from ..conftest import ROOT


def test_ci_cell_is_the_student_t_interval_by_hand():
    values = [1.0, 2.0, 4.0, 7.0]
    m = sum(values) / 4
    sd = math.sqrt(sum((v - m) ** 2 for v in values) / 3)
    half = stats.t.ppf(0.975, 3) * sd / 2  # sqrt(4) = 2
    assert ci_cell(values, ".3f") == f"{m:.3f} ± {half:.3f}" == "3.500 ± 4.210"
    assert ci_cell(values, ".3g", ".2g") == "3.5 ± 4.2"
    assert ci_cell([2.0, np.nan], ".2f") == "2.00"  # one finite value: no interval
    assert ci_cell([np.nan]) == "—"


def test_diff_cell_is_the_signed_mean_and_interval_by_hand():
    d = [-1.0, 0.0, 1.0, 4.0]  # mean 1, sd sqrt(14/3), half = t(0.975, 3) sd / 2
    half = stats.t.ppf(0.975, 3) * math.sqrt(14.0 / 3.0) / 2.0
    assert diff_cell(mean_ci(np.array(d))) == f"+1.000 [{1 - half:+.3f}, {1 + half:+.3f}]"
    assert diff_cell(mean_ci(np.array(d)), "+.1f") == "+1.0 [-2.4, +4.4]"



@pytest.mark.parametrize("est, fmts, expected", [
    # paper001's paired table: three significant digits in the mean, two in the bounds
    # (0.0297 -> 0.030 -> "0.03": the g format drops trailing zeros)
    (Estimate(0.01234, -0.0051, 0.0297, 5), ("+.3g", "+.2g"), "+0.0123 [-0.0051, +0.03]"),
    (Estimate(-0.857, -17.7, 16.0, 2), ("+.3g", "+.2g"), "-0.857 [-18, +16]"),
    (Estimate(1234.5, 5.0, 2500.0, 3), ("+.3g", "+.2g"), "+1.23e+03 [+5, +2.5e+03]"),
    # paper002's terms and the best-classical table: one format, "+" and the term's own
    (Estimate(-0.42, -2.6494, 1.8091, 5), ("+.3f",), "-0.420 [-2.649, +1.809]"),
    (Estimate(0.04, -0.83, 0.91, 12), ("+.1f",), "+0.0 [-0.8, +0.9]"),
    (Estimate(-0.4519, -1.2871, 0.4333, 12), ("+.2f",), "-0.45 [-1.29, +0.43]"),
    # the default (science pages, paper004): a bound that rounds to zero keeps its sign
    (Estimate(0.0, -0.0004, 0.0004, 4), (), "+0.000 [-0.000, +0.000]"),
])
def test_diff_cell_in_the_formats_of_its_callers(est, fmts, expected):
    assert diff_cell(est, *fmts) == expected
    if len(fmts) == 1:  # no bound format: the bounds take the mean's
        assert diff_cell(est, fmts[0], fmts[0]) == expected


def test_pooled_rows_by_hand_on_three_trajectories():
    # the fuzzy filter halves the EKF's error on 1 and 2 and equals it on 6: over all three
    # 100 (1 - 9/12) = +25 %; without 6 the ratio is 1/2 on every run, so every bootstrap
    # resample gives +50 % too.  Half widths t(0.975, n-1) sd / sqrt(n): EKF (2, 4, 6)
    # 4.3027 * 2 / sqrt(3) = 4.97, (2, 4) 12.706 * sqrt(2) / sqrt(2) = 12.71; fuzzy (1, 2, 6)
    # 4.3027 * sqrt(7) / sqrt(3) = 6.57, (1, 2) 12.706 * sqrt(0.5) / sqrt(2) = 6.35
    piv = pd.DataFrame({"ekf": [2.0, 4.0, 6.0], "fuzzy": [1.0, 2.0, 6.0]},
                       index=pd.Index([1, 2, 6], name="trajectory"))
    ekf, fuzzy = pooled_rows(piv, ["ekf", "fuzzy"], "ekf", piv.index != 6, label=str.upper)
    assert ekf == ["EKF", "2.00", "4.00", "6.00", "4.00 ± 4.97", "", "3.00 ± 12.71", ""]
    assert fuzzy[:5] == ["FUZZY", "1.00", "2.00", "6.00", "3.00 ± 6.57"]
    assert fuzzy[5].startswith("+25.0 % [")
    assert fuzzy[6:] == ["1.50 ± 6.35", "+50.0 % [+50.0, +50.0]"]
    # no subset: the pooled cells over all runs only, in the format asked for
    assert pooled_rows(piv, ["fuzzy"], "ekf", fmt=".1f") == [
        ["fuzzy", "1.0", "2.0", "6.0", "3.0 ± 6.6", fuzzy[5]]]


def test_stopped_early_counts_per_scenario_zeros_included():
    dfs = {"a": pd.DataFrame({"completed": [1.0, 0.4, 0.99, 1.0]}),
           "b": pd.DataFrame({"completed": [1.0, 1.0]})}
    assert stopped_early(dfs) == "a 2, b 0"

def test_improvement_cell_from_one_pair_is_the_bare_change():
    assert improvement_cell([2.0], [1.5]) == "+25.0 %"
    lo_hi = improvement_cell([2.0, 2.0, 2.0], [1.0, 1.0, 1.0])
    assert lo_hi == "+50.0 % [+50.0, +50.0]"


@pytest.mark.parametrize("name", list(PAGES))
def test_every_page_has_its_docs_file_section_and_generator(name):
    page = PAGES[name]
    doc = ROOT / page.doc
    assert doc.is_file(), doc
    if page.marker is not None:
        text = doc.read_text(encoding="utf-8")
        begin, end = markers(page.marker)
        assert text.count(begin) == 1 and text.count(end) == 1
        assert text.index(begin) < text.index(end)
    build = importlib.import_module(page.module).build
    assert callable(build)
    assert set(page.small) <= set(build.__code__.co_varnames)
    assert set(page.full) <= set(build.__code__.co_varnames)


def test_replace_section_keeps_the_rest_and_refuses_a_page_without_it():
    text = "head\n<!-- results:begin -->\nold\n<!-- results:end -->\ntail\n"
    assert replace_section(text, "results", "new") == \
        "head\n<!-- results:begin -->\nnew\n<!-- results:end -->\ntail\n"
    with pytest.raises(Exception, match="no section"):
        replace_section("no markers here", "results", "new")


def test_unknown_page_exits_2_naming_the_known_ones(capsys):
    assert main(["docs", "regenerate", "paper999"]) == 2
    err = capsys.readouterr().err
    assert "paper999" in err and "paper000" in err and "science" in err


def test_small_budget_needs_out_and_leaves_docs_alone(capsys):
    assert main(["docs", "regenerate", "paper000", "--budget", "small"]) == 2
    assert "--out" in capsys.readouterr().err


def test_work_is_refused_by_a_page_that_runs_no_studies(tmp_path, capsys):
    assert main(["docs", "regenerate", "paper000", "--budget", "small",
                 "--out", str(tmp_path / "out"), "--work", str(tmp_path / "j")]) == 2
    err = capsys.readouterr().err
    assert "--work" in err and "paper000" in err
    assert not (tmp_path / "out" / "paper000.md").exists()


def test_missing_recordings_name_the_dataset_before_any_run(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FUZZYNAV_DATA", str(tmp_path))
    assert main(["docs", "regenerate", "paper004", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "'akit'" in err and str(tmp_path) in err and "fuzzynav data fetch akit" in err
    assert not (tmp_path / "out" / "paper004.md").exists()


def test_docs_list_names_every_page(capsys):
    assert main(["docs", "list"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in PAGES)


def test_paper000_regenerates_to_out_through_the_cli(tmp_path, monkeypatch, sim_cache):
    """A cut-down paper000 (EKF and FAKF, one seed per scenario) to --out: the docs page is
    untouched, the copy differs only inside its section, and the section has the tables."""
    from fuzzynav.papers.paper000 import page

    monkeypatch.setattr(page, "FILTERS", {"EKF": "ekf", "FAKF, paper rules": "fakf"})
    monkeypatch.setitem(PAGES, "paper000", dataclasses.replace(
        PAGES["paper000"], small={"mc": 1, "mc_variants": 1}))
    monkeypatch.setenv("FUZZYNAV_CACHE", str(sim_cache))
    doc = ROOT / "docs" / "paper000.md"
    before = doc.read_bytes()
    assert main(["docs", "regenerate", "paper000", "--budget", "small",
                 "--out", str(tmp_path)]) == 0
    assert doc.read_bytes() == before
    new = (tmp_path / "paper000.md").read_text(encoding="utf-8")
    begin, end = markers("results")
    old = before.decode()
    assert new.split(begin)[0] == old.split(begin)[0]
    assert new.split(end)[1] == old.split(end)[1]
    section = new.split(begin)[1].split(end)[0]
    assert "Generated by `fuzzynav docs regenerate paper000 --budget small`" in section
    assert "| east position (m) |" in section and "| FAKF, paper rules |" in section
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind


def test_only_is_refused_where_it_does_not_apply(capsys):
    # a page without parts, an unknown part, and with --budget small: exit 2, one line each
    assert main(["docs", "regenerate", "paper000", "--only", "auv"]) == 2
    assert "no parts" in capsys.readouterr().err
    assert main(["docs", "regenerate", "science", "--only", "nope"]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "split" in err and "auv" in err
    assert main(["docs", "regenerate", "science", "--only", "auv", "--budget", "small"]) == 2
    assert "--only" in capsys.readouterr().err


def test_only_reruns_just_the_named_parts(monkeypatch, tmp_path, capsys):
    import fuzzynav.pages.science as science

    calls = []
    monkeypatch.setattr(science, "regenerate_parts",
                        lambda parts, data: calls.append((parts, data)))
    monkeypatch.setenv("FUZZYNAV_DATA", str(tmp_path))
    assert main(["docs", "regenerate", "science", "--only", "split,auv"]) == 0
    assert calls == [(("split", "auv"), tmp_path)]
    assert "science.md" in capsys.readouterr().out


def test_docs_list_shows_the_parts(capsys):
    assert main(["docs", "list"]) == 0
    out = capsys.readouterr().out
    assert all(f"--only {p}" in out for p in PAGES["science"].parts)
