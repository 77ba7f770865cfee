"""Tuning variance on the pages (the one helper of the car split, the A-KIT folds and the
paper pages), on hand-made score frames."""
import json

import numpy as np
import pandas as pd
import pytest

from fuzzynav.metrics import crossed_ci, mean_ci
from fuzzynav.pages import science_split_tunings as st


def _scores(diff, seeds=(1, 2, 3), scenario="set", classical=None):
    """A frame of tuning x seed rows: design = 1 + diff[t][j], 'a' = 1, 'b' = 1 + (0.5 in
    tuning 1 else -0.1) unless ``classical`` gives per tuning the (a, b) scores."""
    rows = []
    for t, row in enumerate(diff):
        a, b = (classical or {}).get(t, (1.0, 1.5 if t == 1 else 0.9))
        for seed, d in zip(seeds, row):
            rows += [{"scenario": scenario, "seed": seed, "tuning": t, "filter": f,
                      "score": v} for f, v in (("fz", a + d), ("a", a), ("b", b))]
    return pd.DataFrame(rows)


def test_tuning_files_and_specs():
    assert st.tuning_file("rules/x_tuned.json", 0) == "rules/x_tuned.json"
    assert st.tuning_file("rules/x_tuned.json", 2) == "rules/x_tuned_t2.json"
    assert st.tuning_spec("fuzzy-ship@rules/p.json+rules/l.json", 1) == \
        "fuzzy-ship@rules/p_t1.json+rules/l_t1.json"
    assert st.tuning_spec("ekf", 1) == "ekf"


def test_tunings_present_needs_every_file(tmp_path):
    for name in ("a.json", "b.json", "a_t1.json", "b_t1.json", "a_t2.json"):
        (tmp_path / name).write_text("{}")
    assert st.tunings_present(["a.json", "b.json"], 3, tmp_path) == [0, 1]


def test_differences_against_a_fixed_filter_per_tuning():
    s = _scores([[0.1, 0.2, 0.3], [0.0, -0.1, 0.1]])
    table, refs = st.differences(s, "set", "fz", best={0: "a", 1: "b"})
    assert refs == ["a", "b"]
    # tuning 1 against b = 1.5: design 1 + d - 1.5
    np.testing.assert_allclose(table, [[0.1, 0.2, 0.3], [-0.5, -0.6, -0.4]], atol=1e-12)


def test_differences_choose_the_lowest_mean_of_the_pool_per_tuning():
    s = _scores([[0.1, 0.2, 0.3], [0.0, 0.0, 0.0]])
    _, refs = st.differences(s, "set", "fz", pool=["a", "b"])
    assert refs == ["b", "a"]  # b = 0.9 beats a in tuning 0, a = 1 beats b = 1.5 in 1


def test_differences_refuse_other_seeds_and_missing_filters():
    s = pd.concat([_scores([[0.0] * 3]),
                   _scores([[0.0] * 3], seeds=(7, 8, 9)).assign(tuning=1)])
    with pytest.raises(ValueError, match="different seeds"):
        st.differences(s, "set", "fz", pool=["a"])
    with pytest.raises(ValueError, match="did not run"):
        st.differences(_scores([[0.0] * 3]), "set", "fz", best={0: "zz"})
    with pytest.raises(ValueError, match="best"):
        st.differences(_scores([[0.0] * 3]), "set", "fz")


def test_spread_between_tunings_and_seeds():
    x = np.array([[1.0, 2.0, 3.0], [3.0, 4.0, 5.0]])
    between, within = st.spread(x)
    # row means 2 and 4: SD sqrt(2); each row's SD over seeds is 1
    assert between == pytest.approx(np.sqrt(2.0))
    assert within == pytest.approx(1.0)
    assert np.isnan(st.spread(x[:1])[0])


def test_lines_give_each_tuning_the_crossed_pool_and_the_spread():
    diff = [[-0.10, -0.12, -0.08], [-0.02, -0.04, 0.00], [-0.06, -0.09, -0.03]]
    s = _scores(diff, classical={t: (1.0, 2.0) for t in range(3)})
    lines, tally = st.tunings_lines(s, ["set"], ["fz"], best={0: "a", 1: "a", 2: "a"})
    row = lines[2]
    for r in diff:
        e = mean_ci(np.array(r))
        assert f"{e.mean:+.3f} [{e.lo:+.3f}, {e.hi:+.3f}]" in row
    pooled = crossed_ci(np.array(diff))
    assert f"{pooled.mean:+.3f} [{pooled.lo:+.3f}, {pooled.hi:+.3f}]" in row
    between = np.std([np.mean(r) for r in diff], ddof=1)
    assert f"| {between:.3f} |" in row
    assert sum(tally["fz"].values()) == 1
    assert "| a |" in row  # the same filter every tuning: named once


def test_pooled_verdict_is_wider_than_any_one_tuning():
    # every tuning wins clearly, but the tunings disagree by far more than the seeds:
    # pooled over tunings the interval must cover zero-ish uncertainty of the tuning mean
    diff = [[-0.30, -0.31, -0.29], [-0.01, -0.02, -0.00], [-0.15, -0.16, -0.14]]
    s = _scores(diff, classical={t: (1.0, 2.0) for t in range(3)})
    _, tally = st.tunings_lines(s, ["set"], ["fz"], best={t: "a" for t in range(3)})
    assert tally["fz"]["draws with"] == 1


def test_best_on_training_per_tuning(tmp_path):
    for k, (sa, sb) in enumerate(((0.9, 0.8), (0.7, 0.8))):
        (tmp_path / f"p{k}.json").write_text(json.dumps(
            {"train_score": {"ekf-tuned": sa, "vb-tuned": sb}}))
    pool = {"EKF, tuned": "ekf-tuned@x.json", "VB, tuned": "vb-tuned@x.json"}
    got = st.best_on_training({0: tmp_path / "p0.json", 1: tmp_path / "p1.json"}, pool)
    assert got == {0: "VB, tuned", 1: "EKF, tuned"}


def test_score_spread_lines():
    s = pd.DataFrame([{"scenario": "s", "seed": j, "tuning": t, "filter": "f",
                       "score": v}
                      for t, vals in enumerate(([1.0, 3.0], [3.0, 5.0])) for j, v in
                      enumerate(vals)])
    row = st.score_spread_lines(s, ["f"])[2]
    # tuning means 2 and 4 (SD sqrt 2); within a tuning [1, 3] and [3, 5] each have the
    # sample SD sqrt 2 (deviations +-1, one degree of freedom each)
    assert row == f"| f | 2.000 | 4.000 | 2.000 – 4.000 | {np.sqrt(2):.3f} | {np.sqrt(2):.3f} |"


def test_paper_tunings_lines_pairs_each_tuning_with_its_own_best(tmp_path):
    """A page's runs and a fake ``run``: in tuning k the design scores 1 + 0.1 k - 0.2 and
    the classical filters' training scores make 'A' best in tuning 0 and 2, 'B' in 1."""
    from fuzzynav.pages.best_classical import paper_tunings_lines

    (tmp_path / "rules").mkdir()
    (tmp_path / "studies").mkdir()
    train = {0: (0.5, 0.6), 1: (0.7, 0.6), 2: (0.5, 0.9)}
    for k in range(3):
        t = "" if k == 0 else f"_t{k}"
        (tmp_path / f"rules/fz{t}.json").write_text(json.dumps(
            {"provenance": {"objective": {"value": 0.4 + k}}}))
        (tmp_path / f"studies/p{t}.json").write_text(json.dumps(
            {"train_score": {"a-tuned": train[k][0], "b-tuned": train[k][1]}}))
        (tmp_path / f"studies/s{t}.toml").write_text(f"[study]\nseed = {7 + 100 * k}\n")
    filters = {"FZ": "fz@rules/fz.json", "A": "a-tuned@studies/p.json",
               "B": "b-tuned@studies/p.json"}

    def frame(k):  # the classical filters score 1 (A) and 2 (B) whatever the tuning
        return pd.DataFrame([{"seed": j, "filter": f, "score": v} for j in range(4)
                             for f, v in (("FZ", 0.8 + 0.1 * k + 0.01 * j), ("A", 1.0),
                                          ("B", 2.0 if k != 1 else 1.0 + 0.02 * j))])

    seen = []

    def run(specs):
        k = int(specs["A"].split("_t")[1][0])
        seen.append(specs)
        return {"s": frame(k)}

    text = "\n".join(paper_tunings_lines(
        {"s": pd.concat([frame(0), pd.DataFrame([{"seed": 0, "filter": "ref",
                                                  "score": 1.0}])])},
        run, lambda d: d[["scenario", "seed", "filter", "score"]],
        filters=filters, designs=("FZ",), pool=("A", "B"), params="studies/p.json",
        design_files={"FZ": "rules/fz.json"}, studies=["studies/s.toml"], root=tmp_path))
    assert seen[0] == {"FZ": "fz@rules/fz_t1.json", "A": "a-tuned@studies/p_t1.json",
                       "B": "b-tuned@studies/p_t1.json"}
    assert "sampler seeds 7, 107, 207" in text
    row = next(line for line in text.splitlines() if line.startswith("| `s` |"))
    assert "| A, B |" in row  # chosen on training: A, then B, then A
    # tuning 0: FZ - A = -0.2 + 0.01 j (mean -0.185); tuning 1: FZ - B = -0.1 - 0.01 j
    t0 = mean_ci(np.array([-0.2 + 0.01 * j for j in range(4)]))
    t1 = mean_ci(np.array([-0.1 - 0.01 * j for j in range(4)]))
    assert f"{t0.mean:+.3f} [{t0.lo:+.3f}, {t0.hi:+.3f}]" in row
    assert f"{t1.mean:+.3f} [{t1.lo:+.3f}, {t1.hi:+.3f}]" in row
    assert "| FZ | 0.400 | 1.400 | 2.400 | 1.000 |" in text  # training scores, SD 1


def test_paper_tunings_lines_without_further_tunings(tmp_path):
    from fuzzynav.pages.best_classical import paper_tunings_lines

    (tmp_path / "fz.json").write_text("{}")
    out = paper_tunings_lines({}, None, None, filters={"FZ": "fz@fz.json"}, designs=("FZ",),
                              pool=(), params="p.json", design_files={}, studies=[],
                              root=tmp_path)
    assert "not judged" in out[0]


def test_regenerate_held_out_replaces_only_the_two_subsections(tmp_path, monkeypatch):
    from fuzzynav.pages import science_recordings as sc

    (tmp_path / "docs").mkdir()
    page = ("# top\nkept\n" + sc.SPLIT_HEADING + "\nold split\n" + sc.AUV_HEADING
            + "\nold auv\n" + sc.AUV_END + " tail\nend\n")
    (tmp_path / "docs" / "science.md").write_text(page)
    monkeypatch.setattr(sc, "split_section", lambda root, seeds: (
        [sc.SPLIT_HEADING, f"new split {seeds[0]}-{seeds[-1]}"], None))
    monkeypatch.setattr(sc, "auv_section", lambda d: ([sc.AUV_HEADING, "new auv"], None))
    sc.regenerate_held_out(str(tmp_path), tmp_path, mc_recordings=3, parts=("split",))
    got = (tmp_path / "docs" / "science.md").read_text()
    assert got == page.replace("old split", "new split 100-102")
    sc.regenerate_held_out(str(tmp_path), tmp_path, parts=("auv",))
    assert (tmp_path / "docs" / "science.md").read_text() == got.replace("old auv", "new auv")
