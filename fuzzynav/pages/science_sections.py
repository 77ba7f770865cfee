"""Sections of ``docs/science.md`` over several fuzzy designs and tunings.

* :func:`designs_lines` -- every fuzzy design against the best classical baseline of each
  held-out set (paired per seed, 95 % CI), with a tally per design;
* :func:`variance_lines` -- the tuning variance: each tuning's held-out score per filter,
  the spread between tunings, and each design's verdict against the best classical filter
  per tuning;
* :func:`pooled_lines` -- the paired test pooled over tunings, the tuning seed and the test
  seed as crossed random factors (:func:`fuzzynav.metrics.crossed_ci`);
* :func:`budget_lines` -- the budget curves: training and held-out score against the trials
  a study was given, as a table and a figure.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from fuzzynav.pages import scores as sr
from fuzzynav.report import diff_cell

__all__ = ["MARKS", "designs_lines", "design_tally", "variance_lines", "pooled_differences",
           "pooled_lines", "budget_lines", "budget_sentences"]


def _best(scores, scenario, best, pool) -> str:
    """``best`` (one filter chosen beforehand, e.g. on the training runs) or else the best
    classical filter of ``scenario`` among ``pool`` on these scores."""
    return best if best is not None else sr.best_classical(scores, scenario, pool)


def design_tally(scores, scenarios, design, best=None, pool=None) -> dict:
    """Verdict -> count of ``design`` against each set's best classical filter (``best`` for
    every set, else chosen per set among ``pool``: see :func:`designs_lines`)."""
    tally = {"wins against": 0, "draws with": 0, "loses to": 0}
    for s in scenarios:
        v = sr.verdict(sr.paired(scores, s, design, _best(scores, s, best, pool)))
        tally[v] = tally.get(v, 0) + 1
    return tally


#: the table's word for each verdict of :func:`~fuzzynav.pages.scores.verdict`
MARKS = {"wins against": "**win**", "draws with": "draw", "loses to": "loss",
         "is not told apart (one seed) from": "one seed"}


def designs_lines(scores, scenarios, designs, best=None, pool=None, labels=None) -> list:
    """Markdown: scenario x design, the paired difference to the best classical filter.

    Each cell is the mean over the scenario's seeds of the per-seed difference
    ``score(design) - score(best)`` with its 95 % CI, and the verdict
    (:func:`~fuzzynav.pages.scores.verdict`: a win needs the CI below zero and the mean at
    least :data:`~fuzzynav.pages.scores.MIN_EFFECT` below); a tally per design follows.

    Parameters
    ----------
    scores : DataFrame
        ``scenario, seed, filter, score`` (:func:`~fuzzynav.pages.scores.scores_to`).
    scenarios, designs : sequence of str
        The rows and the fuzzy filters compared.
    best : str, optional
        The classical filter to compare with on every scenario, chosen beforehand (on the
        training runs: :func:`~fuzzynav.pages.scores.best_on_training`).  None: per
        scenario, the one with the lowest mean score on these runs (the held-out data,
        which favours the classical side).
    pool : sequence of str, optional
        With ``best`` None, the filters it is chosen from (default: every classical one).
    labels : mapping, optional
        Filter name -> the name printed (default: the filter name, a design's in a code
        span).
    """
    labels = dict(labels or {})

    def name(f, span=True):
        return labels.get(f, f"`{f}`" if span else f)

    lines = ["| scenario | best classical | " + " | ".join(f"{name(d)} − best" for d in designs)
             + " |", "|---|---|" + "---|" * len(designs)]
    for s in scenarios:
        b = _best(scores, s, best, pool)
        cells = []
        for d in designs:
            est = sr.paired(scores, s, d, b)
            cells.append(f"{diff_cell(est)} {MARKS[sr.verdict(est)]}")
        lines.append(f"| `{s}` | {name(b, span=False)} | " + " | ".join(cells) + " |")
    lines += ["", f"| design | wins | draws | losses (of the {len(scenarios)} sets) |",
              "|---|---|---|---|"]
    for d in designs:
        t = design_tally(scores, scenarios, d, best, pool)
        lines.append(f"| {name(d)} | {t['wins against']} | {t['draws with']} | "
                     f"{t['loses to']} |")
    return lines


def variance_lines(per_tuning: dict, designs, classical, scenarios) -> list:
    """Markdown of the tuning variance.

    ``per_tuning``: tuning seed -> scores against ``ekf`` (:func:`~.scores.scores_to`) of
    that tuning's held-out runs; ``designs`` the fuzzy labels, ``classical`` the tuned
    classical filters."""
    from fuzzynav.tuning.tuning_seeds import tuning_spread

    names = [*designs, *classical]
    per, across = tuning_spread(per_tuning, names)
    seeds = list(per_tuning)
    lines = ["Held-out score against the EKF (mean over every held-out run; ± the 95 % CI "
             "over those runs) of each tuning, and the spread between tunings:", "",
             "| filter | " + " | ".join(f"tuning seed {s}" for s in seeds)
             + " | mean | min – max | std between tunings |",
             "|---|" + "---|" * (len(seeds) + 3)]
    for name in names:
        sub = per[per["filter"] == name].set_index("tuning_seed")
        a = across[across["filter"] == name].iloc[0]
        cells = [f"{sub.loc[s, 'score']:.3f} ± {sub.loc[s, 'score_ci']:.3f}" for s in seeds]
        lines.append(f"| `{name}` | " + " | ".join(cells) + f" | {a['mean']:.3f} | "
                     f"{a['min']:.3f} – {a['max']:.3f} | {a['std']:.3f} |")
    lines += ["", "Each fuzzy design against the best classical filter of each held-out set, "
              "per tuning (wins / draws / losses of the sets; the best classical filter "
              "chosen per tuning and set, on the held-out data):", "",
              "| design | " + " | ".join(f"tuning seed {s}" for s in seeds) + " |",
              "|---|" + "---|" * len(seeds)]
    for d in designs:
        cells = []
        for s in seeds:
            t = design_tally(per_tuning[s], scenarios, d)
            cells.append(f"{t['wins against']} / {t['draws with']} / {t['loses to']}")
        lines.append(f"| `{d}` | " + " | ".join(cells) + " |")
    return lines


def pooled_differences(per_tuning: dict, scenario: str, design: str):
    """``(best classical, estimate)``: ``design`` against the classical filter with the
    lowest mean score on ``scenario`` over every tuning, the paired difference per tuning
    and test seed, its CI with both as crossed random factors."""
    from fuzzynav.metrics import crossed_ci

    both = pd.concat([s.assign(tuning_seed=k) for k, s in per_tuning.items()])
    best = sr.best_classical(both, scenario)
    rows = []
    for k, s in per_tuning.items():
        sub = s[s["scenario"] == scenario].pivot(index="seed", columns="filter",
                                                 values="score").sort_index()
        rows.append((sub[design] - sub[best]).to_numpy())
    return best, crossed_ci(np.vstack(rows))


def pooled_lines(per_tuning: dict, scenarios, designs) -> tuple:
    """Markdown rows (scenario x design) of :func:`pooled_differences`, and the tally
    design -> wins against the best classical filter."""
    n = len(per_tuning)
    lines = [f"Each fuzzy design against the best classical filter of each held-out set, "
             f"pooled over the {n} tunings: the paired difference per tuning and test seed, "
             "with a 95 % CI that treats the tuning seed and the test seed as crossed random "
             "factors (two-way random-effects model, Satterthwaite degrees of freedom), so "
             "it covers what another tuning would give, not only other seeds; the best "
             "classical filter is chosen on the mean over every tuning:", "",
             "| scenario | best classical | " + " | ".join(f"`{d}` − best" for d in designs)
             + " |", "|---|---|" + "---|" * len(designs)]
    wins = dict.fromkeys(designs, 0)
    for s in scenarios:
        cells, best = [], None
        for d in designs:
            best, est = pooled_differences(per_tuning, s, d)
            v = sr.verdict(est)
            wins[d] += v == "wins against"
            mark = {"wins against": " **win**", "loses to": " loss"}.get(v, "")
            cells.append(f"{diff_cell(est)}{mark}")
        lines.append(f"| `{s}` | {best} | " + " | ".join(cells) + " |")
    return lines, wins


def _figure(points: pd.DataFrame, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for k, (name, sub) in enumerate(points.groupby("filter", sort=False)):
        g = sub.groupby("trials")
        n = np.array(sorted(g.groups))
        for col, style in (("held_out_score", "-"), ("train_score", ":")):
            m, lo, hi = g[col].mean(), g[col].min(), g[col].max()
            ax.plot(n, m.loc[n], style, marker="o", color=f"C{k}",
                    label=f"{name} ({'held out' if col[0] == 'h' else 'training'})")
            if col[0] == "h":
                ax.fill_between(n, lo.loc[n], hi.loc[n], color=f"C{k}", alpha=0.15)
    ax.set_xscale("log")
    ax.set_xlabel("trials of the study")
    ax.set_ylabel("score (RMS error over the EKF's)")
    ax.set_title("Budget curves (band: min–max over tunings)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def budget_lines(points: pd.DataFrame, fig_path, fig_name: str) -> list:
    """Markdown table of the budget curves and the figure (written to ``fig_path``)."""
    _figure(points, fig_path)
    lines = ["| filter | trials | tunings | training score | held-out score (min – max "
             "over tunings) |", "|---|---|---|---|---|"]
    for (name, n), sub in points.groupby(["filter", "trials"], sort=False):
        h = sub["held_out_score"]
        lines.append(f"| `{name}` | {n} | {len(sub)} | {sub['train_score'].mean():.3f} | "
                     f"{h.mean():.3f} ({h.min():.3f} – {h.max():.3f}) |")
    return [f"![budget curves](figures/{fig_name})", "", *lines]


def budget_sentences(points: pd.DataFrame, tol: float = 0.001) -> list:
    """Where more search stops helping (the smallest budget whose mean held-out score is
    within ``tol`` of the best) and where it overfits (training better and held out worse
    by more than ``tol`` from one budget to the next); changes under ``tol`` are flat."""
    out = []
    for name, sub in points.groupby("filter", sort=False):
        g = sub.groupby("trials")[["train_score", "held_out_score"]].mean().sort_index()
        h, tr = g["held_out_score"], g["train_score"]
        best = int(h.index[(h <= h.min() + tol).to_numpy()][0])
        text = (f"- `{name}`: held-out score {' → '.join(f'{v:.3f}' for v in h)}"
                f" and training {' → '.join(f'{v:.3f}' for v in tr)} at "
                f"{', '.join(str(int(n)) for n in g.index)} trials" + (
                    f"; no budget after {best} improves the held-out score by more than "
                    f"{tol}." if best != int(g.index[-1]) else "."))
        worse = [(int(a), int(b)) for a, b in zip(g.index[:-1], g.index[1:])
                 if tr[b] < tr[a] - tol and h[b] > h[a] + tol]
        if worse:
            text += (" From " + ", ".join(f"{a} to {b}" for a, b in worse) + " trials the "
                     "training score still improves while the held-out score gets worse: "
                     "the search overfits the training runs there.")
        elif best == int(g.index[-1]):
            text += " More search still helped at the largest budget measured."
        elif (h.max() - h.min()) <= tol and (tr.max() - tr.min()) <= tol:
            text += " The search found nothing better than its first trials."
        out.append(text)
    return out
