"""Regenerate docs/paper002.md: paper 002's alignment reproduced, with measured numbers.

    python benchmarks/paper002_results.py [--mc 50] [--mc-variants 20]

Runs the alignment filters on ``paper002`` (``--mc`` seeds) and on each variant
(``--mc-variants`` seeds), with the paper's rules and, when ``rules/paper002_ror_tuned.json``
exists, the tuned ones; draws the misalignment errors with their 3-sigma bounds for the
plain and the fuzzy filter; writes the page (text, tables, figures) atomically.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fuzzynav import units  # noqa: E402
from fuzzynav.align import alignment_run as R  # noqa: E402
from fuzzynav.align.monte_carlo import ALIGN_ROWS, monte_carlo_alignment  # noqa: E402
from fuzzynav.align.scenario import load_alignment_scenario  # noqa: E402
from fuzzynav.papers.claims import claims_for  # noqa: E402
from fuzzynav.fileio import publish  # noqa: E402
from fuzzynav.report import comparison_rows, render  # noqa: E402

DOC = ROOT / "docs" / "paper002.md"
FIG = ROOT / "docs" / "figures"
TUNED = ROOT / "rules" / "paper002_ror_tuned.json"
FILTERS = ["align-kf", "align-kf12", "align-fuzzy", "align-fuzzy-fast"]
VARIANTS = ["paper002-rmismatch", "paper002-sway", "paper002-gusts", "paper002-mems"]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from paper002_text import page  # noqa: E402


def results(name, seeds):
    """Metrics of every filter (and the tuned rules) on one scenario."""
    scn = load_alignment_scenario(name)
    df = monte_carlo_alignment(scn, FILTERS, seeds)
    if TUNED.exists():
        tuned = monte_carlo_alignment(scn, ["align-fuzzy"], seeds, rules=str(TUNED))
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


def figure(name, seed=0) -> str:
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
    FIG.mkdir(parents=True, exist_ok=True)
    path = FIG / f"{name}_misalignment.png"
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, dpi=90)
    plt.close(fig)
    publish(tmp, path)
    return f"figures/{path.name}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mc", type=int, default=50)
    ap.add_argument("--mc-variants", type=int, default=20)
    ap.add_argument("--reuse", metavar="PICKLE",
                    help="keep the Monte-Carlo results in this file and reuse them if present "
                         "(to rewrite the text without rerunning)")
    args = ap.parse_args(argv)
    if args.reuse and Path(args.reuse).exists():
        runs = pd.read_pickle(args.reuse)
    else:
        runs = {"paper002": results("paper002", range(args.mc))}
        for v in VARIANTS:
            runs[v] = results(v, range(args.mc_variants))
        if args.reuse:
            pd.to_pickle(runs, args.reuse)
    tables = {n: table(n, df) for n, (_, df) in runs.items()}
    figs = {n: figure(n) for n in ("paper002", "paper002-rmismatch")}
    text = page(runs, tables, figs, never, args)
    tmp = DOC.with_name(".paper002.md.tmp")
    tmp.write_text(text, encoding="utf-8")
    publish(tmp, DOC)
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
