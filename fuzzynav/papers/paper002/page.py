"""Regenerate docs/paper002.md: paper 002's alignment reproduced, with measured numbers.

    fuzzynav docs regenerate paper002

Runs the alignment filters on ``paper002`` (``--mc`` seeds) and on each variant
(``--mc-variants`` seeds), with the paper's rules and, when ``rules/paper002_ror_tuned.json``
exists, the tuned ones, and, when ``studies/align/paper002_baselines.json`` exists, the
equally tuned classical filter (``align-kf-tuned``, :mod:`.page_tuned`); draws the
misalignment errors with their 3-sigma bounds for the plain and the fuzzy filter; writes
the page (text, tables, figures) atomically.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav import units
from fuzzynav.align import alignment_run as R
from fuzzynav.align.alignment_run import ALIGN_ROWS
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.experiment import monte_carlo
from fuzzynav.papers.claims import claims_for
from fuzzynav.fileio import publish
from fuzzynav.papers.paper002.page_text import TUNED, page
from fuzzynav.papers.paper002.page_tuned import BASELINES, CLASSICAL
from fuzzynav.report import comparison_rows, render

__all__ = ["FILTERS", "VARIANTS", "results", "table", "never", "figure", "build"]

FILTERS = ["align-kf", "align-kf12", "align-fuzzy", "align-fuzzy-fast"]
VARIANTS = ["paper002-rmismatch", "paper002-sway", "paper002-gusts", "paper002-mems"]


def results(name, seeds):
    """Metrics of every filter (and the tuned rules and constants) on one scenario."""
    scn = load_alignment_scenario(name)
    kf_tuned = [f"align-kf-tuned@{BASELINES}"] if BASELINES.exists() else []
    df = monte_carlo(scn, FILTERS + kf_tuned, seeds, seed_runs=R.seed_runs(scn))
    df["filter"] = df["filter"].replace({f: CLASSICAL for f in kf_tuned})
    if TUNED.exists():
        tuned = monte_carlo(scn, ["align-fuzzy"], seeds, seed_runs=R.seed_runs(scn, str(TUNED)))
        tuned["filter"] = "align-fuzzy tuned"
        df = pd.concat([df, tuned], ignore_index=True)
    return scn, df


def table(name, df) -> str:
    filters = list(dict.fromkeys(df["filter"]))
    labels, claims = claims_for(name) if name == "paper002" else ((), {})
    header = ["metric", *filters, *(f"{f} vs align-kf" for f in filters[1:]), *labels]
    return render(header, comparison_rows(df, filters, "align-kf", rows=ALIGN_ROWS,
                                          claims=claims), markdown=True)


def never(df) -> dict:
    return {f: int((g["aligned_pct"] == 0).sum()) for f, g in df.groupby("filter", sort=False)}


def figure(name, fig_dir: Path, seed=0) -> str:
    """Misalignment errors with +-3 sigma for the plain and the fuzzy filter."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scn = load_alignment_scenario(name)
    log = R.simulate(scn, seed)
    ep = R.epochs(scn, log, seed)
    fig, axes = plt.subplots(3, 2, figsize=(10, 8), sharex=True)
    for col, f in enumerate(["align-kf", "align-fuzzy"]):
        out = R.run_align_filter(f, scn, log, ep)
        sig = out.result.sigma("att") / units.ARCMIN
        err = out.error / units.ARCMIN
        for row, axis in enumerate(("east", "north", "up (azimuth)")):
            ax = axes[row, col]
            ax.plot(out.result.time_s, err[:, row], label="error (truth - estimate)")
            ax.fill_between(out.result.time_s, -3 * sig[:, row], 3 * sig[:, row], alpha=0.25,
                            label="±3σ of the filter")
            lim = 3 * max(np.abs(err[60:, row]).max(), sig[-1, row])
            ax.set_ylim(-lim, lim)
            ax.set_ylabel(f"{axis} [arcmin]")
            ax.grid(True, alpha=0.3)
        axes[0, col].set_title(f"{f} on {name}, seed {seed}")
        axes[2, col].set_xlabel("time [s]")
    axes[0, 0].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig_dir.mkdir(parents=True, exist_ok=True)
    path = fig_dir / f"{name}_misalignment.png"
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=90)
    plt.close(fig)
    publish(tmp, path)
    return f"figures/{path.name}"


def build(ctx, mc: int = 50, mc_variants: int = 20, reuse: str | None = None) -> str:
    """The whole page: ``mc`` seeds of paper002, ``mc_variants`` of each variant; ``reuse``
    keeps the Monte-Carlo results in this pickle and reuses them if present (to rewrite the
    text without rerunning)."""
    if reuse and Path(reuse).exists():
        runs = pd.read_pickle(reuse)
    else:
        runs = {"paper002": results("paper002", range(mc))}
        for v in VARIANTS:
            runs[v] = results(v, range(mc_variants))
        if reuse:
            pd.to_pickle(runs, reuse)
    tables = {n: table(n, df) for n, (_, df) in runs.items()}
    figs = {n: figure(n, ctx.fig_dir) for n in ("paper002", "paper002-rmismatch")}
    return page(runs, tables, figs, never, ctx.command)
