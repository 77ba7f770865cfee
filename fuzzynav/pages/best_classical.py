"""The papers' "best equally tuned classical filter" section: each tuned fuzzy design
against the classical filters tuned with the same budget, training runs and objective
(a baseline study's ``studies/*_baselines.json``), paired per seed with 95 % CIs.

The table itself is :func:`fuzzynav.pages.science_sections.designs_lines`, the one used by
the science page; this module only puts a paper page's runs into its shape and says how the
best classical filter was chosen.
"""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from fuzzynav.pages import scores as sr
from fuzzynav.pages import science_split_tunings as st
from fuzzynav.pages.science_sections import MARKS, designs_lines
# re-exported: the pages import it from here
from fuzzynav.pages.science_split_tunings import provenance_score
from fuzzynav.report import diff_cell

__all__ = ["paper_lines", "provenance_score", "paired_terms_lines", "labelled",
           "further_runs"]


def paper_lines(dfs: dict, *, designs, pool, params, metrics, weights=None,
                labels=None, ref: str = "ekf", score_text: str = "",
                design_train=None) -> list:
    """Markdown of the section: the scores, then the paired table twice (best classical
    chosen on the training runs, and per scenario on the page's own runs).

    Parameters
    ----------
    dfs : dict
        Scenario name -> the page's runs of it (:func:`fuzzynav.experiment.monte_carlo`).
    designs : sequence of str
        The tuned fuzzy filters (specs, as in the runs' ``filter`` column).
    pool : sequence of str
        The equally tuned classical filters (specs), each tuned in the baseline study whose
        output is ``params``.
    params : path
        That study's output; its ``train_score`` picks the best on the training runs.
    metrics, weights
        The score of a run: the weighted mean of these metrics' ratios to ``ref``
        (:func:`~fuzzynav.pages.scores.scores_to`); ``score_text`` says it in words.
    labels : mapping, optional
        Spec -> the name printed.
    design_train : mapping, optional
        Design spec -> its training score (:func:`provenance_score`), printed beside the
        classical filters' ones.
    """
    labels = dict(labels or {})
    scores = sr.scores_to(pd.concat(list(dfs.values()), ignore_index=True), ref, metrics,
                          weights)
    scenarios = list(dfs)
    best, train = sr.best_on_training(params, pool)
    name = labels.get(best, best)
    order = [*designs, *pool]
    table = sr.ratio_table(scores.assign(filter=scores["filter"].map(lambda f: labels.get(f, f))),
                           [labels.get(f, f) for f in order], scenarios)
    trained = {**dict(design_train or {}), **train}
    train_line = ("Training scores (the objective on the training runs, as the studies "
                  "report them): " + ", ".join(f"{labels.get(f, f)} {v:.3f}"
                                               for f, v in trained.items()) + ".")
    return [
        train_line, "",
        f"Score of a run: {score_text or 'the mean of the RMS ratios to ' + ref} on the same "
        "run (< 1 beats it); mean over seeds ± the 95 % CI:", "", *table, "",
        f"**Chosen on the training runs.** The best equally tuned classical filter is the one "
        f"with the lowest training score in `{params}` (the objective every filter of that "
        f"study was tuned on): {name} ({train[best]:.3f}). Each cell is the mean over the "
        "scenario's seeds of the per-seed difference of scores, design − best, with its "
        f"95 % CI; a win or a loss needs the CI to exclude zero and |mean| ≥ "
        f"{sr.MIN_EFFECT}:", "",
        *designs_lines(scores, scenarios, designs, best=best, labels=labels), "",
        "**Chosen on these runs.** The same with, per scenario, the equally tuned classical "
        "filter of lowest mean score on the page's own (held-out) runs — a choice made on "
        "the test data, which favours the classical side:", "",
        *designs_lines(scores, scenarios, designs, pool=pool, labels=labels)]


def paired_terms_lines(df: pd.DataFrame, scenarios, design: str, best: str, terms,
                       notes=None) -> list:
    """Markdown table: per scenario, the paired difference ``design - best`` of each term.

    Each cell is the mean over the scenario's seeds of the per-seed difference (same seed =
    same simulated data) with its 95 % CI (:func:`~fuzzynav.pages.scores.paired`) and the
    verdict mark (:func:`~fuzzynav.pages.scores.verdict`; negative favours ``design``).

    Parameters
    ----------
    df : DataFrame
        One row per run: ``scenario``, ``seed``, ``filter`` and a column per term.
    scenarios : sequence of str
        The rows, in order.
    design, best : str
        The two filters compared (values of ``filter``).
    terms : sequence of (str, str, str)
        ``(header, column, format spec)`` of each compared quantity.
    notes : mapping, optional
        Scenario -> words printed after its name (e.g. that it was a training set).
    """
    notes = dict(notes or {})
    lines = ["| scenario | seeds | " + " | ".join(f"{h} (95 % CI)" for h, _, _ in terms)
             + " |", "|---|---|" + "---|" * len(terms)]
    for s in scenarios:
        cells, n = [], 0
        for _, col, fmt in terms:
            est = sr.paired(df.assign(score=df[col]), s, design, best)
            n = max(n, est.n)
            cells.append(f"{diff_cell(est, '+' + fmt)} {MARKS[sr.verdict(est)]}")
        note = f" ({notes[s]})" if s in notes else ""
        lines.append(f"| `{s}`{note} | {n} | " + " | ".join(cells) + " |")
    return lines


def paper_tunings_lines(dfs: dict, run, score, *, filters: dict, designs, pool, params,
                        design_files: dict, studies, train_score=provenance_score,
                        unit: str = "seeds", root=None,
                        plain_ref: str = "the score above: against an untuned filter, the "
                                         "same in every tuning") -> list:
    """A paper page's tuning variance: each tuned design against the best equally tuned
    classical filter of the same tuning (chosen on that tuning's training scores), per
    tuning and pooled over tunings (:func:`fuzzynav.pages.science_split_tunings.
    tunings_section`), or a note when the further tunings' files are absent.

    Parameters
    ----------
    dfs : dict
        Scenario -> the page's runs of the first tuning, ``filter`` the labels of
        ``filters`` (every design and pool filter, and the reference ``score`` needs).
    run : callable
        ``run(specs)`` (label -> spec of one further tuning's designs and pool filters) ->
        scenario -> their runs on the page's seeds, ``filter`` the labels.
    score : callable
        A frame of runs (with ``scenario``) -> ``scenario, seed, filter, score`` (e.g.
        :func:`~fuzzynav.pages.scores.scores_to` against an untuned filter, the same in
        every tuning: its rows of the first tuning are reused).
    filters : dict
        Label -> the first tuning's spec (tuning k's: :func:`~fuzzynav.pages.
        science_split_tunings.tuning_spec`).
    params : str
        The first tuning's baseline parameter file (its ``train_score`` picks the best).
    design_files : dict
        Design label -> the first tuning's rule file (``train_score(path)``: its training
        score).
    studies : sequence of str
        The first tuning's study files (their ``_t<k>`` files give the sampler seeds).
    plain_ref : str
        What the score of a run is measured against, in words.
    """
    from fuzzynav.pages.common import REPO_ROOT

    root = Path(root or REPO_ROOT)
    tuned = [*designs, *pool]
    files = [f for label in tuned for f in filters[label].partition("@")[2].split("+")]
    ks = st.tunings_present(files, st.N_TUNINGS, root)
    if len(ks) < 2 or ks[0] != 0:
        return [f"*Further tunings not judged: the `_t1`/`_t2` files of {', '.join(files)} "
                "are absent.*", ""]
    parts = []
    for k in ks:
        frames = dfs if k == 0 else run({f: st.tuning_spec(filters[f], k) for f in tuned})
        for s, df in frames.items():
            rest = dfs[s][~dfs[s]["filter"].isin(tuned)]  # the untuned: the same runs
            one = df if k == 0 else pd.concat([df, rest], ignore_index=True)
            parts.append(one.assign(scenario=s, tuning=k))
    runs = pd.concat(parts, ignore_index=True)
    scores = pd.concat([score(runs[runs["tuning"] == k]).assign(tuning=k) for k in ks],
                       ignore_index=True)
    best = st.best_on_training({k: root / st.tuning_file(params, k) for k in ks},
                               {f: filters[f] for f in pool})
    train = {d: [train_score(root / st.tuning_file(design_files[d], k)) for k in ks]
             for d in designs}
    for f in pool:
        name = filters[f].partition("@")[0]
        train[f] = [json.loads((root / st.tuning_file(params, k)).read_text())
                    ["train_score"][name] for k in ks]
    intro = (f"**Over {len(ks)} tunings.** Every tuned filter of this section, fuzzy and "
             f"classical, tuned {len(ks)} times with the same budget, training runs and "
             "objective, nothing changed but the sampler seed ("
             f"{st.seeds_text(studies, ks, root)}; the further "
             "tunings' study files and outputs carry `_t1`, `_t2`). Each tuned design "
             "against the equally tuned classical filter with the lowest training score "
             "of the same tuning")
    labels = {f: f for f in tuned}
    return st.tunings_section(scores, list(dfs), list(designs), intro=intro, unit=unit,
                              best=best, plain=scores, plain_ref=plain_ref,
                              spread_filters=tuned, labels=labels, train=train)


def labelled(df: pd.DataFrame, specs: dict) -> pd.DataFrame:
    """``df`` with the specs of its ``filter`` column replaced by their labels.

    Parameters
    ----------
    df : DataFrame
        Runs (:func:`fuzzynav.experiment.monte_carlo`), ``filter`` the specs.
    specs : dict
        Label -> spec; a filter that is no spec of it keeps its name.

    Returns
    -------
    DataFrame
        A copy of ``df``.
    """
    back = {v: k for k, v in specs.items()}
    return df.assign(filter=df["filter"].map(lambda f: back.get(f, f)))


def further_runs(seeds: dict, cache):
    """The ``run`` of :func:`paper_tunings_lines` for a page of simulated scenarios.

    Parameters
    ----------
    seeds : dict
        Scenario -> the page's seeds on it (the keys in the page's order).
    cache : Path
        Simulation cache directory.

    Returns
    -------
    callable
        ``run(specs)`` (label -> spec) -> scenario -> :func:`fuzzynav.experiment.
        monte_carlo` of those specs on its seeds, ``filter`` the labels (:func:`labelled`).
    """
    from fuzzynav.experiment import monte_carlo

    def run(specs):
        return {s: labelled(monte_carlo(s, list(specs.values()), seeds[s], cache_dir=cache),
                            specs) for s in seeds}
    return run
