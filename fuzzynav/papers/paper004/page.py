"""The result tables and figures of docs/paper004.md: paper 004 (SINS/DVL, Huber, APSO) in
simulation and on the eight A-KIT AUV recordings.

Runs every filter on the same seeds of the ``paper004`` family (seeds 200-207 at the full budget,
none used in training) and on trajectories 1-8 of ``$FUZZYNAV_DATA/akit`` (skipped with a
note when absent), writes the figures into docs/figures/ and rewrites the section between
``<!-- results:begin -->`` and ``<!-- results:end -->`` of docs/paper004.md.  About ten
minutes on two cores.  Usage: ``fuzzynav docs regenerate paper004``; ``build(ctx,
real_only=True)`` reruns the A-KIT part alone (a loader change) and keeps the simulated
tables.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav import plots
from fuzzynav.papers.paper004.claims import PAPER004_IMPROVEMENT, PAPER004_LAKE
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import monte_carlo, run_on_log
from fuzzynav.metrics import errors_vs_trajectory
from fuzzynav.pages.common import machine, stopped_early
from fuzzynav.report import ci_cell, improvement_cell, pooled_rows, render
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario

__all__ = ["R", "FILTERS", "SCENARIOS", "APSO", "REAL_FILTERS", "simulate_family", "paper_table",
           "family_table", "real_data", "real_table", "sim_figures", "akit_figures", "REAL_HEAD",
           "sim_part", "kept_sim_part", "require_recordings", "real_part", "build"]

R = "rules/"
FILTERS = {  # label -> filter spec (options below)
    "KF (EKF)": "ekf",
    "ST-EKF": "ekf-st",
    "Huber γ = 0.8 (paper)": "huber-0.8",
    "Huber γ = 1.345": "huber",
    "Sage–Husa": "sage-husa",
    "VB": "vb",
    "APSO (Q/R tuned on A-KIT 1–4)": "apso@studies/paper004_apso.json",  # see APSO
    "fuzzy R-scaling (tuned)": f"fakf@{R}paper004_fuzzy_dvl.json",
}
SCENARIOS = ("paper004", "paper004-clean", "paper004-heavy", "paper004-dropouts")
APSO = "apso@studies/paper004_apso.json"
#: on A-KIT every filter here is untrained; the tuned ones (APSO, fuzzy) are judged on the
#: trajectories they were not trained on, in the held-out section (page_heldout.py)
REAL_FILTERS = ("ekf", "ekf-st", "huber", "sage-husa", "vb")


def _cell(values, digits=2) -> str:
    return ci_cell(values, f".{digits}f")


_imp = improvement_cell


def simulate_family(mc, cache) -> dict:
    """Metrics of every filter on every scenario (huber-0.8 is ``huber`` with gamma 0.8)."""
    seeds = range(200, 200 + mc)
    specs = [s for s in FILTERS.values() if s != "huber-0.8"]
    out = {}
    for scn in SCENARIOS:
        df = monte_carlo(scn, specs, seeds, cache_dir=cache)
        h = monte_carlo(scn, ["huber"], seeds, options={"gamma": 0.8}, cache_dir=cache)
        out[scn] = pd.concat([df, h.assign(filter="huber-0.8")], ignore_index=True)
    return out


def paper_table(df) -> str:
    """Paper 004's lake-test layout: KF, Huber, APSO (ours with CI) beside the claims."""
    piv = {k: df.pivot_table(index="seed", columns="filter", values=k)
           for k in PAPER004_LAKE}
    apso, hub = APSO, "huber-0.8"
    rows = []
    for key, label in (("mean_pos_h_m", "mean horizontal error (m)"),
                       ("max_pos_h_m", "max horizontal error (m)")):
        p = piv[key]
        kf, hb, ap = PAPER004_LAKE[key]
        rows.append([label, _cell(p["ekf"]), _cell(p[hub]), _cell(p[apso]),
                     _imp(p["ekf"], p[apso]), _imp(p[hub], p[apso]), f"{kf:g}", f"{hb:g}",
                     f"{ap:g}"])
    head = ["", "KF (ours)", "Huber 0.8 (ours)", "APSO (ours)", "APSO vs KF (ours)",
            "APSO vs Huber (ours)", "KF (claim)", "Huber (claim)", "APSO (claim)"]
    note = (f"Paper's stated improvements of APSO on the mean error: "
            f"{-PAPER004_IMPROVEMENT['vs KF']:.2f} % vs KF, "
            f"{-PAPER004_IMPROVEMENT['vs Huber']:.2f} % vs Huber (lake test, claim).")
    return render(head, rows, markdown=True) + "\n\n" + note


def family_table(dfs, key="mean_pos_h_m") -> str:
    """Every filter on every scenario: mean ± 95 % CI and the paired change vs the EKF."""
    head = ["filter"] + [f"`{s}`" for s in dfs]
    rows = []
    for label, spec in FILTERS.items():
        cells = []
        for df in dfs.values():
            p = df.pivot_table(index="seed", columns="filter", values=key)
            cells.append(_cell(p[spec]) + ("" if spec == "ekf" else
                                          f" ({_imp(p['ekf'], p[spec])})"))
        rows.append([label] + cells)
    return render(head, rows, markdown=True)


def real_data(data_dir):
    """Per-trajectory metrics of every filter on A-KIT 1-8 and the EKF run's results."""
    from fuzzynav.filters.named import parse_filter_spec
    from fuzzynav.realdata.akit import run_all
    from fuzzynav.realdata.loaders.akit_recording import load_akit

    recs = load_akit(data_dir, "1-8")
    frames, ekf_results = [], None
    for spec in REAL_FILTERS:
        name, opts = parse_filter_spec(spec)
        df, results = run_all(recs, name, opts)
        frames.append(df.assign(spec=spec))
        ekf_results = results if spec == "ekf" else ekf_results
    return recs, pd.concat(frames, ignore_index=True), ekf_results


def real_table(df, key="rms_pos_h_m") -> str:
    """Per trajectory, pooled (mean ± CI over trajectories) and paired change vs the EKF."""
    piv = df.pivot_table(index="trajectory", columns="spec", values=key)
    head = ["filter"] + [f"{t}" for t in piv.index] + ["all 8", "vs EKF (all 8)",
                                                       "1-5, 7, 8", "vs EKF (without 6)"]
    rows = pooled_rows(piv, REAL_FILTERS, "ekf", piv.index != 6,
                       label=lambda spec: spec.split("@")[0])
    return render(head, rows, markdown=True)


def sim_figures(cache, fig_dir: Path) -> list:
    """Convergence/inertia of the APSO and simulated error curves."""
    out = []
    fig, ax = plots.plt.subplots(figsize=(6, 3.2))
    for fold, style in (("paper004_apso", "o"), ("paper004_apso_rev", "s")):
        doc = json.loads((Path("studies") / f"{fold}.json").read_text())
        hist = pd.DataFrame(doc["history"]["apso"])
        train = ",".join(sorted({r[0].split(":")[-1] for r in doc["train"]}))
        ax.plot(hist["iteration"], hist["best"], f"{style}-", label=f"best, trained on {train}")
        ax.plot(hist["iteration"], hist["swarm_mean"], f"{style}--", alpha=0.6,
                label=f"swarm mean, trained on {train}")
    ax.set_xlabel("iteration")
    ax.set_ylabel("train RMS position / EKF's")
    ax2 = ax.twinx()
    ax2.plot(hist["iteration"], hist["inertia"], "k:", label="inertia weight")
    ax2.set_ylabel("inertia weight (dotted)")
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    out.append(plots.save(fig, fig_dir / "paper004_apso_convergence.png"))
    log = simulate(load_scenario("paper004"), 200, cache)
    fig, ax = plots.plt.subplots(figsize=(7, 3.2))
    for label in ("KF (EKF)", "Huber γ = 1.345", "APSO (Q/R tuned on A-KIT 1–4)"):
        name, _, rules = FILTERS[label].partition("@")
        res = run_on_log(log, name, {"rules": [rules]} if rules else {}).result
        err = errors_vs_trajectory(res, log.truth)
        ax.plot(err.time_s, np.hypot(err.pos_m[:, 0], err.pos_m[:, 1]), lw=1, label=label)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("paper004, seed 200")
    fig.tight_layout()
    out.append(plots.save(fig, fig_dir / "paper004_sim_error.png"))
    return out


def akit_figures(recs, ekf_results, fig_dir: Path) -> list:
    """The EKF's tracks over the reference tracks, and its errors (none without data)."""
    if not recs:
        return []
    from fuzzynav.realdata.akit_figures import error_figure, map_figure

    return [plots.save(map_figure(recs, ekf_results, "EKF"), fig_dir / "paper004_akit_map.png"),
            plots.save(error_figure(recs, ekf_results, "EKF"),
                       fig_dir / "paper004_akit_error.png")]


REAL_HEAD = "### The eight A-KIT trajectories"


def sim_part(ctx, mc) -> tuple[list, list]:
    """The simulated tables' lines and figures."""
    dfs = simulate_family(mc, ctx.cache)
    return [
        f"Generated by `{ctx.command}` ({machine()}). Simulation: seeds "
        f"200–{199 + mc} of every scenario (the tuned fuzzy rules and APSO "
        "multipliers were trained on A-KIT trajectories 1–4, so every simulated run is "
        "held out for them). Runs that stopped early: "
        + stopped_early(dfs) + ".", "",
        "### The paper's lake-test table, in simulation (`paper004`)", "",
        paper_table(dfs["paper004"]), "",
        "### Every filter on the family: mean horizontal error (m), paired change vs the "
        "EKF (positive = smaller error)", "", family_table(dfs), ""], sim_figures(ctx.cache, ctx.fig_dir)


def kept_sim_part(fig_dir: Path) -> tuple[list, list]:
    """``real_only``: the simulated tables as the page has them (they read no recording)
    and their figures as they are."""
    body = Path("docs/paper004.md").read_text().split("<!-- results:begin -->")[1]
    kept = body.split(REAL_HEAD)[0].strip("\n").split("\n") + [""]
    return kept, [fig_dir / "paper004_apso_convergence.png", fig_dir / "paper004_sim_error.png"]


def require_recordings(data: Path) -> None:
    """Raise :class:`FuzzynavError` naming the dataset when A-KIT is not at ``data``."""
    if not (data / "IMU_trajectory1.csv").is_file():
        raise FuzzynavError(f"{data}: the A-KIT recordings (dataset 'akit') are missing; "
                            "fetch them with `fuzzynav data fetch akit` or set $FUZZYNAV_DATA")


def real_part(data, fig_dir: Path) -> tuple[list, list]:
    """The A-KIT tables' lines (untuned filters, held-out studies) and figures, or a
    sentence saying they were skipped when the recordings are absent."""
    if not (data / "IMU_trajectory1.csv").is_file():
        return [f"(A-KIT recordings not found at {data}: real-data tables skipped.)", ""], []
    from fuzzynav.papers.paper004.page_heldout import heldout_frame, section, tunings_lines

    recs, real, ekf_results = real_data(data)
    return [f"{REAL_HEAD}: horizontal RMS (m) against the post-processed reference", "",
            "Per trajectory, pooled over the eight (mean ± 95 % CI over trajectories) "
            "and without trajectory 6 (see above), with the paired change against the "
            "EKF on the same trajectories. The source reports only that its learned "
            "filter beats a plain EKF by more than 49.5 % in position (claim).", "",
            real_table(real), "",
            "End error as % of the distance travelled:", "",
            real_table(real, "end_pos_h_pct"), ""] + section(heldout_frame()) + \
        tunings_lines(), \
        akit_figures(recs, ekf_results, fig_dir)


def build(ctx, mc: int = 8, real: bool = True, real_only: bool = False) -> str:
    """The results section and figures: seeds 200.. (``mc``) of every simulated scenario and
    A-KIT 1-8 (``real``: the recordings are required; False: skipped if absent)."""
    if real:
        require_recordings(ctx.data_dir / "akit")  # before the simulations, not after
    parts, figs = kept_sim_part(ctx.fig_dir) if real_only else sim_part(ctx, mc)
    real_lines, real_figs = real_part(ctx.data_dir / "akit", ctx.fig_dir)
    parts, figs = parts + real_lines, figs + real_figs
    parts += ["Figures: " + ", ".join(f"[{p.name}](figures/{p.name})" for p in figs), ""]
    parts += [f"![{p.stem}](figures/{p.name})" for p in figs]
    return "\n".join(parts)
