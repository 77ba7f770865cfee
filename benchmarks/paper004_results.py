"""The result tables and figures of docs/paper004.md: paper 004 (SINS/DVL, Huber, APSO) in
simulation and on the eight A-KIT AUV recordings.

Runs every filter on the same seeds of the ``paper004`` family (seeds 200-209 by default,
none used in training) and on trajectories 1-8 of ``$FUZZYNAV_DATA/akit`` (skipped with a
note when absent), writes the figures into docs/figures/ and rewrites the section between
``<!-- results:begin -->`` and ``<!-- results:end -->`` of docs/paper004.md.  About ten
minutes on two cores.  Usage: ``python benchmarks/paper004_results.py [--mc 10]``;
``--real-only`` reruns the A-KIT part alone (a loader change) and keeps the simulated tables.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_results  # noqa: E402

from fuzzynav import plots  # noqa: E402
from fuzzynav.papers.paper004.claims import PAPER004_IMPROVEMENT, PAPER004_LAKE  # noqa: E402
from fuzzynav.experiment import monte_carlo, run_on_log  # noqa: E402
from fuzzynav.metrics import errors_vs_trajectory, improvement_ci, mean_ci  # noqa: E402
from fuzzynav.report import render  # noqa: E402
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
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
#: trajectories they were not trained on, in the held-out section (paper004_heldout.py)
REAL_FILTERS = ("ekf", "ekf-st", "huber", "sage-husa", "vb")
FIG = ROOT / "docs" / "figures"


def _cell(values, digits=2) -> str:
    est = mean_ci(np.asarray(values, float))
    return f"{est.mean:.{digits}f} ± {est.half_width:.{digits}f}"


def _imp(base, cand) -> str:
    imp = improvement_ci(np.asarray(base, float), np.asarray(cand, float))
    return f"{imp.mean:+.1f} % [{imp.lo:+.1f}, {imp.hi:+.1f}]"


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
    keep = piv.index != 6
    rows = []
    for spec in REAL_FILTERS:
        col = piv[spec]
        rows.append([spec.split("@")[0]] + [f"{v:.2f}" for v in col]
                    + [_cell(col), "" if spec == "ekf" else _imp(piv["ekf"], col),
                       _cell(col[keep]), "" if spec == "ekf" else
                       _imp(piv["ekf"][keep], col[keep])])
    return render(head, rows, markdown=True)


def sim_figures(cache) -> list:
    """Convergence/inertia of the APSO and simulated error curves."""
    out = []
    fig, ax = plots.plt.subplots(figsize=(6, 3.2))
    for fold, style in (("paper004_apso", "o"), ("paper004_apso_rev", "s")):
        doc = json.loads((ROOT / "studies" / f"{fold}.json").read_text())
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
    out.append(plots.save(fig, FIG / "paper004_apso_convergence.png"))
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
    out.append(plots.save(fig, FIG / "paper004_sim_error.png"))
    return out


def akit_figures(recs, ekf_results) -> list:
    """The EKF's tracks over the reference tracks, and its errors (none without data)."""
    if not recs:
        return []
    from fuzzynav.realdata.akit_figures import error_figure, map_figure

    return [plots.save(map_figure(recs, ekf_results, "EKF"), FIG / "paper004_akit_map.png"),
            plots.save(error_figure(recs, ekf_results, "EKF"), FIG / "paper004_akit_error.png")]


REAL_HEAD = "### The eight A-KIT trajectories"


def sim_part(mc, cache) -> tuple[list, list]:
    """The simulated tables' lines and figures."""
    dfs = simulate_family(mc, cache)
    failed = {k: int((df["completed"] < 1).sum()) for k, df in dfs.items()}
    return [
        f"Generated by `benchmarks/paper004_results.py` ({machine()}). Simulation: seeds "
        f"200–{199 + mc} of every scenario (the tuned fuzzy rules and APSO "
        "multipliers were trained on A-KIT trajectories 1–4, so every simulated run is "
        "held out for them). Runs that stopped early: "
        + ", ".join(f"{k} {v}" for k, v in failed.items()) + ".", "",
        "### The paper's lake-test table, in simulation (`paper004`)", "",
        paper_table(dfs["paper004"]), "",
        "### Every filter on the family: mean horizontal error (m), paired change vs the "
        "EKF (positive = smaller error)", "", family_table(dfs), ""], sim_figures(cache)


def kept_sim_part() -> tuple[list, list]:
    """``--real-only``: the simulated tables as the page has them (they read no recording)
    and their figures as they are."""
    body = (ROOT / "docs" / "paper004.md").read_text().split("<!-- results:begin -->")[1]
    kept = body.split(REAL_HEAD)[0].strip("\n").split("\n") + [""]
    return kept, [FIG / "paper004_apso_convergence.png", FIG / "paper004_sim_error.png"]


def real_part(data) -> tuple[list, list]:
    """The A-KIT tables' lines (untuned filters, held-out studies) and figures."""
    if not (data / "IMU_trajectory1.csv").is_file():
        return [f"(A-KIT recordings not found at {data}: real-data tables skipped.)", ""], []
    from paper004_heldout import heldout_frame, section

    recs, real, ekf_results = real_data(data)
    return [f"{REAL_HEAD}: horizontal RMS (m) against the post-processed reference", "",
            "Per trajectory, pooled over the eight (mean ± 95 % CI over trajectories) "
            "and without trajectory 6 (see above), with the paired change against the "
            "EKF on the same trajectories. The source reports only that its learned "
            "filter beats a plain EKF by more than 49.5 % in position (claim).", "",
            real_table(real), "",
            "End error as % of the distance travelled:", "",
            real_table(real, "end_pos_h_pct"), ""] + section(heldout_frame()), \
        akit_figures(recs, ekf_results)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mc", type=int, default=10)
    ap.add_argument("--real-only", action="store_true",
                    help="rerun the A-KIT part alone, keeping the page's simulated tables")
    args = ap.parse_args(argv)
    os.chdir(ROOT)
    cache = Path(os.environ.get("FUZZYNAV_CACHE", tempfile.mkdtemp()))
    parts, figs = kept_sim_part() if args.real_only else sim_part(args.mc, cache)
    data = Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets")) / "akit"
    real_lines, real_figs = real_part(data)
    parts, figs = parts + real_lines, figs + real_figs
    parts += ["Figures: " + ", ".join(f"[{p.name}](figures/{p.name})" for p in figs), ""]
    parts += [f"![{p.stem}](figures/{p.name})" for p in figs]
    text = "\n".join(parts)
    write_results(ROOT / "docs" / "paper004.md", text)
    print(text)


if __name__ == "__main__":
    main()
