"""The result tables and figures of docs/paper003.md: the paper-003 ship reproduced.

Runs every filter on the same seeds of ``paper003`` and of its variants and rewrites the
section between ``<!-- results:begin -->`` and ``<!-- results:end -->`` of docs/paper003.md
(tables with 95 % confidence intervals, the paper's claims beside) and the figures
``docs/figures/paper003_*.png``.  The issue's table is 50 seeds of ``paper003``
(``--mc 50``, the default); a run of one filter costs a few seconds (the page states the
measured cost and the counts actually used), so on a loaded machine pass fewer.
Usage: ``nice python benchmarks/paper003_results.py [--mc 50] [--mc-variants 10]``.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_results  # noqa: E402

from fuzzynav import plots  # noqa: E402
from fuzzynav.papers.paper003.claims import PAPER003  # noqa: E402
from fuzzynav.experiment import monte_carlo, run_on_log  # noqa: E402
from fuzzynav.filters.named import parse_filter_spec  # noqa: E402
from fuzzynav.metrics import errors_vs_trajectory, mean_ci  # noqa: E402
from fuzzynav.report import render  # noqa: E402
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TUNED = ("rules/paper003_rscale_tuned_pol.json", "rules/paper003_rscale_tuned_log.json")
FILTERS = {  # short label -> filter spec
    "EKF": "ekf",
    "fuzzy R-scaling (paper 002 rules)": "fuzzy-ship",
    "fuzzy R-scaling, tuned": "fuzzy-ship@" + "+".join(TUNED),
    "Sage–Husa": "sage-husa",
    "VB": "vb",
    "EKF, true noise (oracle)": "ekf-true",
}
ROWS = (("heading (deg)", "rms_heading_deg"), ("horizontal velocity (m/s)", "rms_vel_h_mps"),
        ("horizontal position (m)", "rms_pos_h_m"),
        ("final horizontal position (m)", "final_pos_h_m"))
VARIANTS = ("paper003-current", "paper003-clouds", "paper003-noon", "paper003-storm")


def _cell(values) -> str:
    est = mean_ci(values)
    return f"{est.mean:.3f} ± {est.half_width:.3f}"


def family_table(df, filters) -> str:
    """One scenario: every filter's RMS (mean ± 95 % CI) per row, the paper's claim beside."""
    head = ["RMS error"] + list(filters) + ["paper 003 (claim)"]
    rows = []
    for label, key in ROWS:
        piv = df.pivot_table(index="seed", columns="filter", values=key)
        rows.append([label] + [_cell(piv[spec].to_numpy()) for spec in filters.values()]
                    + [PAPER003.get(key, "—")])
    return render(head, rows, markdown=True)


def ratio_table(dfs, filters) -> str:
    """Mean ratio to the EKF of heading / horizontal velocity / horizontal position RMS."""
    head = ["filter"] + [f"{s}: hdg / vel / pos" for s in dfs]
    rows = []
    for label, spec in filters.items():
        cells = []
        for df in dfs.values():
            parts = []
            for key in ("rms_heading_deg", "rms_vel_h_mps", "rms_pos_h_m"):
                piv = df.pivot_table(index="seed", columns="filter", values=key)
                parts.append(f"{mean_ci((piv[spec] / piv['ekf']).to_numpy()).mean:.2f}")
            cells.append(" / ".join(parts))
        rows.append([label] + cells)
    return render(head, rows, markdown=True)


def figures(filters, cache) -> list:
    """Error curves of seed 1000 on paper003 and on the clouds variant."""
    out = []
    for name in ("paper003", "paper003-clouds"):
        log = simulate(load_scenario(name), 1000, cache)
        errs = {}
        for label, spec in filters.items():
            if label.startswith(("EKF", "fuzzy")):
                base, own = parse_filter_spec(spec)
                errs[label] = errors_vs_trajectory(run_on_log(log, base, own).result, log.truth)
        path = ROOT / "docs" / "figures" / f"{name.replace('-', '_')}_errors.png"
        plots.save(plots.error_curves(errs, f"{name}, seed 1000"), path)
        out.append(path.relative_to(ROOT / "docs"))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mc", type=int, default=50, help="seeds of paper003 (issue: 50)")
    ap.add_argument("--mc-variants", type=int, default=10, help="seeds of each variant")
    args = ap.parse_args(argv)
    os.chdir(ROOT)
    cache = Path(os.environ.get("FUZZYNAV_CACHE", tempfile.mkdtemp()))
    filters = {k: v for k, v in FILTERS.items()
               if "tuned" not in k or all(Path(f).is_file() for f in TUNED)}
    specs = list(filters.values())
    t0 = time.perf_counter()
    dfs = {"paper003": monte_carlo("paper003", specs, range(1000, 1000 + args.mc),
                                   cache_dir=cache)}
    for name in VARIANTS:
        dfs[name] = monte_carlo(name, specs, range(2000, 2000 + args.mc_variants),
                                cache_dir=cache)
    n_runs = sum(len(df) for df in dfs.values())
    per_run = (time.perf_counter() - t0) / n_runs  # simulation included: what a seed costs
    failed = {k: int((df["completed"] < 1).sum()) for k, df in dfs.items()}
    figs = figures(filters, cache)
    parts = [f"Generated by `benchmarks/paper003_results.py` ({machine()}). `paper003`: seeds "
             f"1000–{999 + args.mc}; variants: seeds 2000–{1999 + args.mc_variants} (the "
             "study trained on seeds 0–1 of paper003-current and paper003-clouds). "
             f"{n_runs} runs of one filter, {per_run:.1f} s each (wall clock, simulation "
             "included, on the machine as loaded then). Runs that stopped early: " + ", ".join(f"{k} {v}" for k, v in failed.items()) + ".", ""]
    for name, df in dfs.items():
        parts += [f"### `{name}`", "", family_table(df, filters), ""]
    parts += ["### Every filter, every scenario: mean ratio of RMS error to the EKF "
              "(< 1 beats the EKF)", "", ratio_table(dfs, filters), ""]
    parts += [f"![{f.stem}]({f.as_posix()})" for f in figs]
    text = "\n".join(parts)
    write_results(ROOT / "docs" / "paper003.md", text)
    print(text)


if __name__ == "__main__":
    main()
