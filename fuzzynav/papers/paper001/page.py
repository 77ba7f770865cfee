"""The result tables and the figure of docs/paper001.md: paper 001's system, pairs and controllers.

Runs every filter on the same seeds of ``paper001`` and of its variants, and rewrites the
section between ``<!-- results:begin -->`` and ``<!-- results:end -->`` of docs/paper001.md
and the figure ``docs/figures/paper001_heading.png`` (heading error through the magnetic
disturbance).  Filters are a dict of label -> filter spec; more can be added from the
caller without editing this file, e.g. the generic banks:
``build(ctx, add=["federated (one local per kind)=federated"])``.
Usage: ``fuzzynav docs regenerate paper001``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav.papers.paper001.claims import PAPER001_COMBINED
from fuzzynav.papers.paper001.page_tuned import TUNED_BANK, TUNED_FILTERS, paired_table, \
    tuned_lines, usage_table
from fuzzynav.experiment import run_on_log
from fuzzynav.filters.named import parse_filter_spec
from fuzzynav.metrics import errors_vs_trajectory
from fuzzynav.pages.common import machine
from fuzzynav.report import ci_cell, render
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario

__all__ = ["TUNED", "HAND_BANK", "FILTERS", "VARIANTS", "ZONE_S", "run_family", "main_table",
           "variant_table", "heading_figure", "shares_figure", "build"]

TUNED = "rules/paper001_mag_tuned.json"
HAND_BANK = ("rules/paper001_beta.json", "rules/paper001_mag.json")
FILTERS = {  # short label -> filter spec; the first is the reference of the ratio table
    "centralized EKF (every sensor)": "centralized",
    "SINS/BDS + polarization": "ekf-bds-pol",
    "SINS/BDS + magnetometer": "ekf-bds-mag",
    "polarization + magnetometer": "ekf-pol-mag",
    "federated (paper 001: 3 locals, no reset, β = 1/3)": "federated-p001",
    "federated, reset": "federated-p001-reset",
    "federated, fuzzy R in the magnetometer's local": "federated-fuzzy",
    "federated, fuzzy β (shares from the locals' NIS)": "federated-fuzzy-beta",
    "federated, fuzzy β + fuzzy R": "federated-fuzzy-beta@" + "+".join(HAND_BANK),
    "federated, tuned β + tuned R": "federated-fuzzy-beta@" + "+".join(TUNED_BANK),
    "centralized, fuzzy R on the magnetometer": "fuzzy-mag",
    "centralized, tuned fuzzy R on the magnetometer": f"fuzzy@{TUNED}",
    "SINS/BDS + magnetometer, fuzzy R": "fuzzy-bds-mag",
    "Sage–Husa (every sensor)": "sage-husa",
    "EKF, true noise (oracle)": "ekf-true",
}
VARIANTS = ("paper001-nodist", "paper001-strong", "paper001-outages")
#: the disturbance zone of paper001 (1-Hz magnetometer: samples 200-300) [s]
ZONE_S = (200.0, 300.0)


def run_family(scenario, filters, seeds, cache) -> pd.DataFrame:
    """Metrics per (filter, seed), with the heading RMS inside the zone."""
    rows = []
    for seed in seeds:
        log = simulate(load_scenario(scenario), int(seed), cache)
        for label, spec in filters.items():
            name, opts = parse_filter_spec(spec)
            out = run_on_log(log, name, opts)
            err = errors_vs_trajectory(out.result, log.truth)
            inside = (err.time_s >= ZONE_S[0]) & (err.time_s < ZONE_S[1])
            zone = np.degrees(np.sqrt(np.mean(err.att_rad[inside, 2] ** 2)))
            rows.append({"filter": label, "seed": int(seed), **out.metrics,
                         "rms_heading_zone_deg": zone})
    return pd.DataFrame(rows)


def _files(spec: str) -> list:
    """The rule files a filter spec names (``NAME@A+B``)."""
    return [f for f in spec.partition("@")[2].split("+") if f]


def _cell(values) -> str:
    return ci_cell(values, ".3g", ".2g")


def main_table(df) -> str:
    """East/north position and heading (whole run, inside the zone) per filter."""
    keys = ("rms_pos_e_m", "rms_pos_n_m", "rms_heading_deg", "rms_heading_zone_deg")
    rows = []
    for label in df["filter"].unique():
        sub = df[df["filter"] == label]
        rows.append([label, *(_cell(sub[k]) for k in keys),
                     f"{int((sub['completed'] < 1).sum())}"])
    rows.append(["paper 001, combined (claim)", f"{PAPER001_COMBINED['rms_pos_e_m']:g}",
                 f"{PAPER001_COMBINED['rms_pos_n_m']:g}", "—", "—", "—"])
    head = ["filter", "east (m)", "north (m)", "heading (°)", "heading, samples 200–300 (°)",
            "stopped early"]
    return render(head, rows, markdown=True)


def variant_table(dfs) -> str:
    """Horizontal position and heading RMS per scenario (mean ± 95 % CI)."""
    head = ["filter"] + [f"{s}: horizontal (m) / heading (°)" for s in dfs]
    rows = []
    for label in next(iter(dfs.values()))["filter"].unique():
        cells = []
        for df in dfs.values():
            sub = df[df["filter"] == label]
            cells.append(f"{_cell(sub['rms_pos_h_m'])} / {_cell(sub['rms_heading_deg'])}")
        rows.append([label] + cells)
    return render(head, rows, markdown=True)


def heading_figure(filters, seed, cache, path) -> Path:
    """Heading error of some filters and of the magnetometer itself through the zone."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fuzzynav import plots

    log = simulate(load_scenario("paper001"), seed, cache)
    fig, ax = plt.subplots(figsize=(8, 4))
    mag = log.sensors["mag"]
    ax.plot(mag.time_s, np.degrees(mag.meta["err_heading_rad"]), ".", ms=2, color="0.6",
            label="magnetometer heading error")
    for label, spec in filters.items():
        name, opts = parse_filter_spec(spec)
        err = errors_vs_trajectory(run_on_log(log, name, opts).result, log.truth)
        ax.plot(err.time_s, np.degrees(err.att_rad[:, 2]), lw=1.2, label=label)
    ax.axvspan(*ZONE_S, color="orange", alpha=0.12, label="disturbance zone")
    ax.set(xlabel="time (s)", ylabel="heading error (°)", ylim=(-2.0, 10.0),
           title=f"paper001, seed {seed}: heading error through the magnetic disturbance")
    ax.legend(fontsize=7, loc="upper left")
    return plots.save(fig, path)


def shares_figure(seed, cache, path) -> Path:
    """The information shares the fuzzy controller gives the three locals through the zone."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fuzzynav import plots

    log = simulate(load_scenario("paper001"), seed, cache)
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for spec, style in (("federated-fuzzy-beta", "-"),
                        ("federated-fuzzy-beta@" + "+".join(HAND_BANK), "--")):
        res = run_on_log(log, *parse_filter_spec(spec)).result
        for k, name in enumerate(("BDS", "polarization", "magnetometer")):
            ax.plot(res.time_s, res.locals.beta[:, k], style, lw=1.1, color=f"C{k}",
                    label=f"{name}{'' if style == '-' else ', with fuzzy R'}")
    ax.axvspan(*ZONE_S, color="orange", alpha=0.12, label="disturbance zone")
    ax.set(xlabel="time (s)", ylabel="share β", ylim=(0.0, 0.7),
           title=f"paper001, seed {seed}: shares set by the fuzzy controller")
    ax.legend(fontsize=7, loc="upper left", ncol=2)
    return plots.save(fig, path)


def build(ctx, mc: int = 50, mc_variants: int = 20, add=()) -> str:
    """The results section and the two figures; ``add``: more ``"LABEL=SPEC"`` filters."""
    cache = ctx.cache
    filters = {k: v for k, v in {**FILTERS, **TUNED_FILTERS}.items()
               if all(Path(f).is_file() for f in _files(v))}
    filters.update(dict(a.split("=", 1) for a in add))
    seeds = {"paper001": range(1000, 1000 + mc),
             **{name: range(2000, 2000 + mc_variants) for name in VARIANTS}}
    dfs = {name: run_family(name, filters, s, cache) for name, s in seeds.items()}
    done = {}  # (label, spec) -> scenario -> runs: each further tuning's filter runs once

    def run(specs):  # further tunings' filters on the page's seeds
        for item in specs.items():
            if item not in done:
                done[item] = {s: run_family(s, dict([item]), seeds[s], cache) for s in dfs}
        return {s: pd.concat([done[item][s] for item in specs.items()], ignore_index=True)
                for s in dfs}

    main_df = dfs["paper001"]
    shown = {k: v for k, v in filters.items() if v in ("centralized", "ekf-bds-pol",
                                                       "ekf-bds-mag", "fuzzy-mag",
                                                       "federated-p001",
                                                       "federated-fuzzy",
                                                       "federated-fuzzy-beta")}
    fig = heading_figure(shown, 1000, cache, ctx.fig_dir / "paper001_heading.png")
    fig_b = shares_figure(1000, cache, ctx.fig_dir / "paper001_shares.png")
    return "\n".join([
        f"Generated by `{ctx.command}` ({machine()}). `paper001`: seeds "
        f"1000–{999 + mc}; variants: seeds 2000–{1999 + mc_variants} (none used "
        "in training). Mean ± 95 % CI over seeds.", "",
        "### Paper 001's figures (`paper001`, disturbance of 8° at samples 200–300)", "",
        main_table(main_df), "",
        "### The variants: horizontal position and heading RMS", "", variant_table(dfs), "",
        "### Each fuzzy layer against the same filter without it (paired per seed)", "",
        "Mean over seeds of the per-seed difference, fuzzy − counterpart, of the horizontal "
        "position RMS and the heading RMS, with its 95 % CI (< 0: the fuzzy layer helps).",
        "", paired_table(dfs, filters), "",
        "### How much the adaptive filters still use the magnetometer (`paper001`)", "",
        "The R factor is the magnetometer's R over its nominal value, per epoch (the fuzzy "
        "controllers' running factor; Sage–Husa's and VB's estimated heading R); "
        "'undisturbed' are the epochs the simulator shows outside the zone. Medians over "
        "the seeds; filters that keep R constant are left out. A controller that holds R "
        "ten times above nominal where nothing is wrong has switched the sensor off.", "",
        usage_table(main_df, filters), "",
        *tuned_lines(dfs, filters, run), "",
        f"![heading error through the disturbance](figures/{fig.name})", "",
        f"![the shares of federated-fuzzy-beta through the disturbance](figures/{fig_b.name})"])
