"""docs/science_recordings.csv carries every tuning's rows of the recordings sections and a
rerun section replaces only its own rows (fuzzynav.pages.science_recordings)."""
import pandas as pd

from fuzzynav.pages import science_recordings as sr


def _runs(scenario, filters, value):
    return pd.DataFrame({"scenario": scenario, "seed": [0, 1] * len(filters),
                         "filter": [f for f in filters for _ in (0, 1)], "score": value})


def test_tuning_rows_stack_every_split_and_tuning():
    frames = {"a": {0: _runs("a", ["x", "y"], 1.0), 1: _runs("a", ["x"], 2.0)},
              "b": {0: _runs("b", ["x"], 3.0), 2: _runs("b", ["x"], 4.0)}}
    rows = sr.tuning_rows(frames)
    assert len(rows) == 4 + 2 + 2 + 2
    got = rows.groupby(["scenario", "tuning"])["score"].first().to_dict()
    assert got == {("a", 0): 1.0, ("a", 1): 2.0, ("b", 0): 3.0, ("b", 2): 4.0}


def test_splice_rows_replaces_only_the_rerun_scenarios(tmp_path):
    path = tmp_path / "rec.csv"
    # an older file: no tuning column, so its rows are the first tuning's
    pd.concat([_runs("car", ["ekf"], 5.0), _runs("a", ["x"], 9.0)]).to_csv(path, index=False)
    new = sr.tuning_rows({"a": {0: _runs("a", ["x"], 1.0), 1: _runs("a", ["x"], 2.0)}})
    out = sr.splice_rows(path, new)
    back = pd.read_csv(path)
    assert len(back) == len(out) == 2 + 4
    assert set(back.loc[back["scenario"] == "car", "tuning"]) == {0}
    assert back.loc[back["scenario"] == "car", "score"].tolist() == [5.0, 5.0]
    assert sorted(back.loc[back["scenario"] == "a", "score"]) == [1.0, 1.0, 2.0, 2.0]
    assert not list(tmp_path.glob("*.tmp*"))  # written through a temporary file


def test_splice_replaces_one_part_and_refuses_a_page_without_it():
    import pytest

    from fuzzynav.errors import FuzzynavError

    page = ("top\n" + sr.SPLIT_HEADING + "\nold split\n" + sr.AUV_HEADING + "\nold auv\n"
            + sr.AUV_END + " tail\n")
    once = sr.splice(page, "auv", [sr.AUV_HEADING, "new auv"])
    assert once == page.replace("old auv", "new auv")
    assert sr.splice(once, "auv", [sr.AUV_HEADING, "new auv"]) == once  # idempotent
    assert sr.splice(page, "split", [sr.SPLIT_HEADING, "s"]) == page.replace("old split", "s")
    with pytest.raises(FuzzynavError, match="'auv' part"):
        sr.splice("top\n" + sr.AUV_HEADING + "\nno end mark\n", "auv", ["x"])
