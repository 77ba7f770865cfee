"""The result tables and the figure of docs/paper001.md: paper 001's system, pairs and controllers.

Runs every filter on the same seeds of ``paper001`` and of its variants, and rewrites the
section between ``<!-- results:begin -->`` and ``<!-- results:end -->`` of docs/paper001.md
and the figure ``docs/figures/paper001_heading.png`` (heading error through the magnetic
disturbance).  Filters are a dict of label -> filter spec; more can be added from the
command line without editing this file, e.g. the generic banks:
``--add "federated (one local per kind)=federated"``.
Usage: ``python benchmarks/paper001_results.py [--mc 50] [--mc-variants 20] [--add L=SPEC]``.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_results  # noqa: E402

from fuzzynav.papers.paper001.claims import PAPER001_COMBINED  # noqa: E402
from fuzzynav.experiment import run_on_log  # noqa: E402
from fuzzynav.filters.named import parse_filter_spec  # noqa: E402
from fuzzynav.metrics import errors_vs_trajectory, mean_ci  # noqa: E402
from fuzzynav.report import render  # noqa: E402
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TUNED = "rules/paper001_mag_tuned.json"
#: the share controller and magnetometer R-scaling tuned together in the bank
#: (studies/paper001_beta_tune.toml, exported with --out rules/paper001_beta_tuned.json)
TUNED_BANK = ("rules/paper001_beta_tuned_beta.json", "rules/paper001_beta_tuned_mag.json")
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
    est = mean_ci(np.asarray(values, float))
    return f"{est.mean:.3g} ± {est.half_width:.2g}"


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


def _parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mc", type=int, default=50)
    ap.add_argument("--mc-variants", type=int, default=20)
    ap.add_argument("--add", action="append", default=[], metavar="LABEL=SPEC",
                    help="another filter (e.g. 'federated (no reset)=federated')")
    return ap.parse_args(argv)


def main(argv=None):
    args = _parse(argv)
    os.chdir(ROOT)
    cache = Path(os.environ.get("FUZZYNAV_CACHE", tempfile.mkdtemp()))
    filters = {k: v for k, v in FILTERS.items() if all(Path(f).is_file() for f in _files(v))}
    filters.update(dict(a.split("=", 1) for a in args.add))
    main_df = run_family("paper001", filters, range(1000, 1000 + args.mc), cache)
    dfs = {"paper001": main_df}
    for name in VARIANTS:
        dfs[name] = run_family(name, filters, range(2000, 2000 + args.mc_variants), cache)
    shown = {k: v for k, v in filters.items() if v in ("centralized", "ekf-bds-pol",
                                                       "ekf-bds-mag", "fuzzy-mag",
                                                       "federated-p001",
                                                       "federated-fuzzy",
                                                       "federated-fuzzy-beta")}
    fig = heading_figure(shown, 1000, cache, ROOT / "docs" / "figures" / "paper001_heading.png")
    fig_b = shares_figure(1000, cache, ROOT / "docs" / "figures" / "paper001_shares.png")
    text = "\n".join([
        f"Generated by `benchmarks/paper001_results.py` ({machine()}). `paper001`: seeds "
        f"1000–{999 + args.mc}; variants: seeds 2000–{1999 + args.mc_variants} (none used "
        "in training). Mean ± 95 % CI over seeds.", "",
        "### Paper 001's figures (`paper001`, disturbance of 8° at samples 200–300)", "",
        main_table(main_df), "",
        "### The variants: horizontal position and heading RMS", "", variant_table(dfs), "",
        f"![heading error through the disturbance](figures/{fig.name})", "",
        f"![the shares of federated-fuzzy-beta through the disturbance](figures/{fig_b.name})"])
    doc = ROOT / "docs" / "paper001.md"
    write_results(doc, text)
    print(text)


if __name__ == "__main__":
    main()
