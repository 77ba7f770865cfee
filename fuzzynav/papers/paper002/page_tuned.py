"""The section of docs/paper002.md that sets the tuned fuzzy alignment filter against the
equally tuned classical one (``align-kf-tuned``, ``studies/align/paper002_baselines.toml``):
same budget, sampler and seed, objective and training runs as the fuzzy study
(``studies/align/paper002_tune.toml``), paired per seed with 95 % CIs on every scenario of
the page, in the objective and in each of its terms.
"""
from __future__ import annotations

import json

import pandas as pd

from fuzzynav.align.tune import objective
from fuzzynav.pages import scores as sr
from fuzzynav.pages.best_classical import paired_terms_lines
from fuzzynav.pages.common import REPO_ROOT
from fuzzynav.report import diff_cell

__all__ = ["FUZZY", "CLASSICAL", "TUNED", "BASELINES", "FUZZY_STUDY", "HELD_OUT", "TERMS", "frame",
           "verdicts", "section", "finding"]

#: the labels of the two tuned filters in the page's runs
FUZZY, CLASSICAL = "align-fuzzy tuned", "align-kf tuned"
#: the tuned rule file, the classical study's output and the fuzzy study (its objective's
#: azimuth weight)
TUNED = REPO_ROOT / "rules" / "paper002_ror_tuned.json"
BASELINES = REPO_ROOT / "studies" / "align" / "paper002_baselines.json"
FUZZY_STUDY = REPO_ROOT / "studies" / "align" / "paper002_tune.toml"
#: the scenarios neither study trained on (the training ones are rmismatch and sway)
HELD_OUT = ("paper002", "paper002-gusts", "paper002-mems")
#: (header, column, format) of the compared quantities: the objective and its two terms
TERMS = (("objective", "objective", ".3f"), ("alignment time [s]", "align_time_s", ".1f"),
         ("final azimuth [arcmin]", "final_azimuth_arcmin", ".2f"))


def frame(runs: dict, weight: float) -> pd.DataFrame:
    """Every run of the page (``runs``: scenario -> (scenario object, runs)) with its
    ``scenario`` and the study objective (:func:`fuzzynav.align.tune.objective`)."""
    parts = []
    for name, (scn, df) in runs.items():
        obj = [objective(m, scn, weight) for m in df.to_dict("records")]
        parts.append(df.assign(scenario=name, objective=obj))
    return pd.concat(parts, ignore_index=True)


def verdicts(df: pd.DataFrame, scenarios, column: str = "objective") -> dict:
    """Scenario -> the verdict of :data:`FUZZY` against :data:`CLASSICAL` on ``column``."""
    return {s: sr.verdict(sr.paired(df.assign(score=df[column]), s, FUZZY, CLASSICAL))
            for s in scenarios}


def _studies() -> tuple:
    from fuzzynav.tuning.kinds.alignment import load_alignment_config

    return (load_alignment_config(FUZZY_STUDY),
            load_alignment_config(BASELINES.with_suffix(".toml")))


def _setting(acfg) -> str:
    st = acfg.study
    return (f"{st.trials} trials, sampler `{st.sampler}` seed {st.seed}, azimuth weight "
            f"{acfg.azimuth_weight:g}, training runs "
            + ", ".join(sorted({s for s, _ in st.train})) + " seeds "
            + ", ".join(str(d) for d in sorted({d for _, d in st.train})))


def _train() -> tuple:
    """The training objective of the tuned fuzzy and classical filters, as their studies
    recorded it."""
    fz = json.loads(TUNED.read_text())["provenance"]["objective"]["train"]["tuned"]
    return fz, json.loads(BASELINES.read_text())["train_score"]["align-kf-tuned"]


def section(runs: dict) -> str:
    """The markdown section (``runs``: scenario -> (scenario object, the page's runs), with
    the rows :data:`FUZZY` and :data:`CLASSICAL`)."""
    fuzzy, classical = _studies()
    df = frame(runs, fuzzy.azimuth_weight)
    fz, kf = _train()
    params = json.loads(BASELINES.read_text())["filters"]["align-kf-tuned"]
    rest = [s for s in runs if s not in HELD_OUT]
    order = [s for s in HELD_OUT if s in runs] + rest
    notes = {s: "training scenario: seeds 0–1 were tuning runs" for s in rest}
    tally = list(verdicts(df, [s for s in HELD_OUT if s in runs]).values())
    return "\n".join([
        "## The tuned fuzzy filter against the equally tuned classical one", "",
        f"`{FUZZY}` (`rules/paper002_ror_tuned.json`, `studies/align/paper002_tune.toml`: "
        f"{_setting(fuzzy)}) against `{CLASSICAL}` (`align-kf-tuned@studies/align/"
        f"paper002_baselines.json`, `studies/align/paper002_baselines.toml`: "
        f"{_setting(classical)}): the same KF with R = r_all R0 and the velocity and "
        "attitude rows of Q0 times q_vel and q_att, constants searched by the same driver on "
        "the same objective (alignment time / run length + weight × final azimuth error / "
        "threshold, mean over the training runs; lower is better).", "",
        f"Training objective as each study reports it: {FUZZY} {fz:.3f}, {CLASSICAL} "
        f"{kf:.3f}. Tuned constants: "
        + ", ".join(f"`{k}` = {v:.3g}" for k, v in params.items()) + ".", "",
        f"Each cell: the mean over the scenario's seeds of the per-seed difference {FUZZY} − "
        f"{CLASSICAL} (same seed = same simulated data) with its 95 % CI; negative favours "
        "the fuzzy filter. A **win** or a loss needs the CI to exclude zero (and, for the "
        f"objective, |mean| ≥ {sr.MIN_EFFECT}); otherwise a draw.", "",
        *paired_terms_lines(df, order, FUZZY, CLASSICAL, TERMS, notes), "",
        f"On the {len(tally)} held-out scenarios, in the objective, the tuned fuzzy filter "
        f"wins {tally.count('wins against')}, draws {tally.count('draws with')} and loses "
        f"{tally.count('loses to')}.", "", _study_test(fuzzy, classical), "",
        "### Over three tunings", "", *tunings_part(runs, df), ""])


def tunings_part(runs: dict, df: pd.DataFrame) -> list:
    """The two tuned filters over their tunings (``_t1``, ``_t2`` study files and outputs:
    :func:`fuzzynav.pages.best_classical.paper_tunings_lines`), scored by the objective."""
    from fuzzynav.align import alignment_run as R
    from fuzzynav.experiment import monte_carlo
    from fuzzynav.pages.best_classical import paper_tunings_lines

    rel = {FUZZY: f"align-fuzzy@{TUNED.relative_to(REPO_ROOT).as_posix()}",
           CLASSICAL: f"align-kf-tuned@{BASELINES.relative_to(REPO_ROOT).as_posix()}"}
    weight = _studies()[0].azimuth_weight

    def run(specs):
        out = {}
        for name in held:
            scn, d = runs[name]
            seeds = sorted(d["seed"].unique())
            kf = monte_carlo(scn, [specs[CLASSICAL]], seeds, seed_runs=R.seed_runs(scn))
            rules = str(REPO_ROOT / specs[FUZZY].partition("@")[2])
            fz = monte_carlo(scn, ["align-fuzzy"], seeds, seed_runs=R.seed_runs(scn, rules))
            both = pd.concat([kf.assign(filter=CLASSICAL), fz.assign(filter=FUZZY)],
                             ignore_index=True)
            out[name] = frame({name: (scn, both)}, weight).drop(columns="scenario")
        return out

    def train(path):
        return json.loads(path.read_text())["provenance"]["objective"]["train"]["tuned"]

    studies = ["studies/align/paper002_tune.toml", "studies/align/paper002_baselines.toml"]
    # the held-out scenarios only: the page's seeds 0-1 of the others were training runs
    held = [s for s in HELD_OUT if s in runs]
    dfs = {s: df[df["scenario"] == s].drop(columns="scenario") for s in held}
    return paper_tunings_lines(
        dfs, run, lambda d: d.assign(score=d["objective"])[["scenario", "seed", "filter",
                                                            "score"]],
        filters=rel, designs=(FUZZY,), pool=(CLASSICAL,), params=rel[CLASSICAL].split("@")[1],
        design_files={FUZZY: rel[FUZZY].split("@")[1]}, studies=studies,
        train_score=train, plain_ref="the objective itself, lower is better")


def _study_test(fuzzy, classical) -> str:
    """The studies' own held-out runs, scored now (the rule file's provenance holds the
    numbers of the day it was tuned)."""
    from fuzzynav.align.tune import Runs
    from fuzzynav.fuzzy import load_fis
    test, w = Runs(fuzzy.study.test), fuzzy.azimuth_weight
    fz = test.score(load_fis(str(TUNED)), fuzzy.filter, w)[0]
    kf = test.score(None, f"{classical.filter}@{BASELINES}", w)[0]
    plain = test.score(None, "align-kf", w)[0]
    return (f"The studies' own held-out runs ({len(test.items)}: "
            + ", ".join(sorted({s for s, _ in fuzzy.study.test})) + " seeds "
            + ", ".join(str(d) for d in sorted({d for _, d in fuzzy.study.test}))
            + f"), mean objective scored with this version: {FUZZY} {fz:.3f}, {CLASSICAL} "
            f"{kf:.3f}, untuned align-kf {plain:.3f}.")


def finding(runs: dict) -> str:
    """The bullet of "What matches the paper" on the two tuned filters (from ``runs``)."""
    fuzzy, _ = _studies()
    df = frame(runs, fuzzy.azimuth_weight)
    held = [s for s in HELD_OUT if s in runs]
    v = verdicts(df, held)
    words = {"wins against": "wins", "draws with": "draws", "loses to": "loses"}
    per = "; ".join(f"on `{s}` it {words.get(v[s], v[s])} ("
                    + _diff(df, s, "objective", ".3f") + ")" for s in held)
    wins = list(v.values()).count("wins against")
    head = ("no held-out win for the fuzzy layer" if wins == 0
            else f"the fuzzy layer wins {wins} of {len(held)} held-out sets")
    fz, kf = _train()
    return (f"- **Against the equally tuned classical filter — {head}.** Tuned with the same "
            "budget, sampler seed, objective and training runs, `align-kf-tuned` (three "
            "constant noise multipliers) fits the training runs "
            f"{'better' if kf < fz else 'worse'} than the tuned ROR → t rules (objective "
            f"{kf:.3f} against {fz:.3f}). Held out, the tuned fuzzy filter against it, paired "
            f"per seed, objective difference fuzzy − classical with its 95 % CI: {per}. On "
            "`paper002` the "
            "final azimuth error differs by "
            + _diff(df, "paper002", "final_azimuth_arcmin", ".2f") + " arcmin and the "
            "alignment time by " + _diff(df, "paper002", "align_time_s", ".1f") + " s (see "
            "the section below).")


def _diff(df, scenario, column, fmt) -> str:
    est = sr.paired(df.assign(score=df[column]), scenario, FUZZY, CLASSICAL)
    return diff_cell(est, "+" + fmt)
