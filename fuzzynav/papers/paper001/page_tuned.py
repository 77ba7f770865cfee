"""docs/paper001.md's paired sections: each fuzzy controller against its classical
counterpart per seed, the magnetometer's use by the adaptive filters, and the tuned fuzzy
controller against the best equally tuned classical filter.

Paired means: on each seed both filters ran on the same simulated data and initial error,
and the CI is over the per-seed differences (the spread between seeds cancels).  The
magnetometer-use figures are :mod:`fuzzynav.metrics_rscale`'s (``r_use_*``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from fuzzynav.metrics import mean_ci
from fuzzynav.metrics_rscale import OFF_SCALE
from fuzzynav.pages.best_classical import paper_lines, provenance_score
from fuzzynav.report import diff_cell, render

__all__ = ["BASELINES", "TUNED_FILTERS", "PAIRS", "paired_table", "usage_table",
           "tuned_lines", "bank_vs_federated"]

BASELINES = "studies/paper001_baselines.json"
TUNED = "rules/paper001_mag_tuned.json"
TUNED_V1 = "rules/paper001_mag_tuned_v1.json"
#: the share controller and magnetometer R-scaling tuned together in the bank
#: (studies/paper001_beta_tune.toml, exported with --out rules/paper001_beta_tuned.json), and
#: that study's first tuning (no r_use penalty: it switched the magnetometer off)
TUNED_BANK = ("rules/paper001_beta_tuned_beta.json", "rules/paper001_beta_tuned_mag.json")
TUNED_BANK_V1 = ("rules/paper001_beta_tuned_beta_v1.json",
                 "rules/paper001_beta_tuned_mag_v1.json")
BANK_DESIGN = "federated, tuned β + tuned R"
#: the paper's bank, the one the bank study's candidates are ratios to
FEDERATED = "federated (paper 001: 3 locals, no reset, β = 1/3)"
REF = "centralized EKF (every sensor)"
#: the tuned filters of this page (label -> spec), added after the hand-made ones
TUNED_FILTERS = {
    "centralized, tuned fuzzy R, first tuning (no r_use penalty)": f"fuzzy@{TUNED_V1}",
    "federated, tuned β + tuned R, first tuning (no r_use penalty)":
        "federated-fuzzy-beta@" + "+".join(TUNED_BANK_V1),
    "EKF, tuned Q and R": f"ekf-tuned@{BASELINES}",
    "Sage–Husa, tuned": f"sage-husa-tuned@{BASELINES}",
    "VB, tuned": f"vb-tuned@{BASELINES}",
    "Huber, tuned": f"huber-tuned@{BASELINES}",
}
DESIGNS = ("centralized, tuned fuzzy R on the magnetometer", BANK_DESIGN)
POOL = ("EKF, tuned Q and R", "Sage–Husa, tuned", "VB, tuned", "Huber, tuned")
#: (fuzzy filter, the same filter without its fuzzy layer)
PAIRS = (
    ("centralized, fuzzy R on the magnetometer", REF),
    ("centralized, tuned fuzzy R on the magnetometer", REF),
    ("SINS/BDS + magnetometer, fuzzy R", "SINS/BDS + magnetometer"),
    ("federated, fuzzy R in the magnetometer's local",
     "federated (paper 001: 3 locals, no reset, β = 1/3)"),
    ("federated, fuzzy β (shares from the locals' NIS)",
     "federated (paper 001: 3 locals, no reset, β = 1/3)"),
    (BANK_DESIGN, "federated (paper 001: 3 locals, no reset, β = 1/3)"),
)
#: design -> the rule file whose provenance gives its training score
DESIGN_FILES = {DESIGNS[0]: TUNED, BANK_DESIGN: TUNED_BANK[0]}
#: the studies' objective (studies/paper001_tune.toml, paper001_baselines.toml)
SCORE_METRICS = ("rms_pos_m", "rms_vel_mps", "rms_att_deg", "r_use_dev_calm")
SCORE_WEIGHTS = (1.0, 1.0, 1.0, 0.1)
USAGE = (("median_calm", "{:.2f}"), ("median_zone", "{:.2f}"), ("off_calm", "{:.0%}"),
         ("off_zone", "{:.0%}"))


def _paired(df, a, b, key) -> str:
    piv = df.pivot_table(index="seed", columns="filter", values=key)
    est = mean_ci((piv[a] - piv[b]).to_numpy())
    return diff_cell(est, "+.3g", "+.2g")


def paired_table(dfs, filters) -> str:
    """Per pair of :data:`PAIRS` present in ``filters`` and scenario: the mean per-seed
    difference (fuzzy − counterpart) of horizontal position RMS (m) and heading RMS (°),
    each with its 95 % CI."""
    rows = []
    for a, b in PAIRS:
        if a in filters and b in filters:
            rows.append([f"{a} − {b}", *(f"{_paired(df, a, b, 'rms_pos_h_m')} / "
                                         f"{_paired(df, a, b, 'rms_heading_deg')}"
                                         for df in dfs.values())])
    return render(["pair"] + [f"{s}: horizontal (m) / heading (°)" for s in dfs], rows,
                  markdown=True)


def usage_table(df, filters) -> str:
    """Per filter of ``filters`` that adapts the magnetometer's R: the median R factor on
    undisturbed epochs and inside the zone, and the share of epochs with R above ten times
    nominal ('off'), pooled over the seeds of ``df``."""
    rows = []
    for label in filters:
        sub = df[df["filter"] == label]
        if sub.empty or "r_use_median_calm" not in sub:
            continue
        medians = {k: np.nanmedian(sub["r_use_" + k].to_numpy(float)) for k, _ in USAGE}
        if medians["median_calm"] == 1.0 and medians["median_zone"] == 1.0:
            continue  # a constant R (every epoch exactly nominal): nothing to show
        rows.append([label, *(fmt.format(medians[k]) for k, fmt in USAGE)])
    table = render(["filter", "median R factor, undisturbed", "median R factor, zone",
                    "R > 10× nominal, undisturbed", "R > 10× nominal, zone"], rows,
                   markdown=True)
    off = [r[0] for r in rows if float(r[1]) > OFF_SCALE]
    if off:
        table += ("\n\nThese hold the magnetometer's R above ten times nominal on most "
                  "undisturbed epochs, i.e. they have switched the sensor off: "
                  + ", ".join(off) + ".")
    return table


def tuned_lines(dfs, filters, run=None) -> list:
    """The section on the tuned fuzzy controller against the best equally tuned classical
    filter (empty unless every filter of it ran); ``run(specs)`` (label -> spec) -> scenario
    -> runs on the page's seeds: the same over the further tunings."""
    if not all(k in filters for k in (*DESIGNS, *POOL, REF)):
        return []
    return ["### The tuned fuzzy designs against the best equally tuned classical filter", "",
            "The tuned fuzzy R (`studies/paper001_tune.toml`), the bank's share controller and "
            "magnetometer R-scaling tuned together (`studies/paper001_beta_tune.toml`) and "
            "the classical filters "
            f"(`studies/paper001_baselines.toml`, parameters in `{BASELINES}`) were tuned "
            "alike: training runs `paper001-mild`, `-double`, `-strong` and `-cloudy`, seeds "
            "0–2; objective the mean of the position, velocity and attitude RMS ratios to "
            "the EKF plus 0.1 × the magnetometer's R departure from nominal on undisturbed "
            "epochs (`r_use`, the same penalty for every filter that moves R); TPE, seed 0; "
            "Wilcoxon pruner; 120 trials. `paper001-strong` is a training scenario (on other "
            "seeds here): it is not a held-out condition. The centralized EKF is the same "
            "filter as `ekf`, the studies' reference.", "",
            *paper_lines({s: df.assign(scenario=s, filter=df["filter"].map(filters))
                          for s, df in dfs.items()},
                         designs=[filters[d] for d in DESIGNS],
                         pool=[filters[c] for c in POOL], params=BASELINES,
                         metrics=SCORE_METRICS, weights=SCORE_WEIGHTS, ref=filters[REF],
                         labels={v: k for k, v in filters.items()},
                         score_text="the studies' objective (position, velocity, attitude "
                                    "RMS ratios to the centralized EKF and 0.1 × r_use)",
                         design_train={filters[d]: provenance_score(f)
                                       for d, f in DESIGN_FILES.items()}),
            *([] if run is None else ["", "### The same over three tunings", "",
                                      *tunings_part(dfs, filters, run), "",
                                      *bank_vs_federated(dfs, filters, run)])]


def tunings_part(dfs, filters, run) -> list:
    """:func:`fuzzynav.pages.best_classical.paper_tunings_lines` of the tuned fuzzy R and
    the classical filters tuned as it was (``dfs``: scenario -> runs, ``filter`` the
    labels)."""
    from fuzzynav.pages import scores as sr
    from fuzzynav.pages.best_classical import paper_tunings_lines

    studies = ["studies/paper001_tune.toml", "studies/paper001_beta_tune.toml",
               "studies/paper001_baselines.toml"]
    return paper_tunings_lines(
        dfs, run, lambda df: sr.scores_to(df, REF, SCORE_METRICS, SCORE_WEIGHTS),
        filters=filters, designs=DESIGNS, pool=POOL, params=BASELINES,
        design_files=DESIGN_FILES, studies=studies)


def bank_vs_federated(dfs, filters, run) -> list:
    """The β + R bank of each tuning against ``federated-p001``, the bank it adapts (the
    studies' objective against it, so a score is the ratio), per tuning and pooled with
    tuning and seed as crossed random factors
    (:func:`fuzzynav.pages.science_split_tunings.tunings_lines`); empty without both."""
    from fuzzynav.pages import scores as sr
    from fuzzynav.pages import science_split_tunings as st

    if not all(k in filters for k in (BANK_DESIGN, FEDERATED)):
        return []
    parts = []
    for k in st.tunings_present(TUNED_BANK, st.N_TUNINGS):
        frames = dfs if k == 0 else run({BANK_DESIGN: st.tuning_spec(filters[BANK_DESIGN], k)})
        for s, df in frames.items():
            ref = dfs[s][dfs[s]["filter"] == FEDERATED]
            one = df[df["filter"] == BANK_DESIGN]
            runs = pd.concat([one, ref], ignore_index=True).assign(scenario=s)
            parts.append(sr.scores_to(runs, FEDERATED, SCORE_METRICS, SCORE_WEIGHTS)
                         .assign(tuning=k))
    scores = pd.concat(parts, ignore_index=True)
    rows, tally = st.tunings_lines(scores, list(dfs), [BANK_DESIGN],
                                   best=dict.fromkeys(scores["tuning"].unique(), FEDERATED))
    t = tally[BANK_DESIGN]
    return ["**The bank against federated-p001**, the same bank with fixed equal shares and "
            "constant R (the column 'best classical' names it here): the objective above "
            "scored against `federated-p001` on each run (a score is then the ratio to it), "
            "paired difference bank − federated-p001 per tuning and pooled over the tunings "
            "and seeds as crossed random factors:", "", *rows, "",
            f"- Pooled over the tunings (wins / draws / losses of the {len(dfs)} sets): "
            f"{t['wins against']} / {t['draws with']} / {t['loses to']}.", ""]
