"""The held-out recordings of ``docs/science.md``: the car drive and the AUV trajectories.

Called by :mod:`fuzzynav.pages.science` (the section "Held-out recordings"); every part
that lacks its data or its rules is skipped with a sentence on the page saying so.

* **Car drive** (``$FUZZYNAV_DATA/rtklib-drive``, ``--data`` of the script): the protocol of
  ``docs/validation.md`` (fixes with 2 m white noise per axis, 60-s outages every 180 s,
  the shipped mounting) on ``--mc`` noise seeds, each filter on the same noisy fixes of a
  seed.  Compared: the classical filters with the parameters tuned on the *simulated*
  training runs (``studies/paper000_baselines.json``), the paper's fuzzy rules (``fakf``),
  the fuzzy controller tuned on the same simulated runs (``fuzzy-tuned``: trained on
  simulation, judged on a real drive), and, when it exists, a controller tuned on the
  first part of the drive (``--car-rules``, default :data:`CAR_RULES`).  Score per seed:
  the mean of the horizontal-position and velocity RMS ratios to ``ekf-tuned`` with GNSS
  throughout (a recording has no attitude truth); the outage drift is tabulated apart.
  The CI is over noise seeds of one recording, not over recordings.
* **AUV** (``$FUZZYNAV_DATA/akit``): only with recording-trained DVL rules (``--auv-rules``,
  default :data:`AUV_RULES`), judged on the trajectories its provenance holds out (with the
  APSO multipliers of the same fold beside); those trajectories are the pairs, score the
  mean of the horizontal-position and velocity RMS ratios to the EKF with DVL.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pandas as pd

from fuzzynav.pages.common import REPO_ROOT as ROOT

#: rules tuned on a recording, looked for when no path is given
CAR_RULES = ROOT / "rules" / "rtklib_drive_tuned.json"
AUV_RULES = ROOT / "rules" / "paper004_fuzzy_dvl.json"
#: the APSO multipliers of the same training fold (``studies/paper004_apso.toml``)
AUV_APSO = ROOT / "studies" / "paper004_apso.json"
CAR_FILTERS = ("ekf", "ekf-tuned", "als", "sage-husa", "sage-husa-tuned", "vb", "vb-tuned",
               "huber-tuned", "strong-tracking-tuned", "fakf")
AUV_FILTERS = ("ekf", "sage-husa", "vb", "huber")
CAR_METRICS = ("rms_pos_h_m", "rms_vel_mps")
SIM_FUZZY, CAR_FUZZY, AUV_FUZZY = "fuzzy-tuned", "fuzzy-drive", "fuzzy-auv"


def data_root(given=None) -> Path:
    """Where the recordings lie: ``given``, ``$FUZZYNAV_DATA`` or ``../shared/datasets``."""
    if given:
        return Path(given)
    return Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets"))


def _car_specs(params: Path, sim_rules: Path, car_rules, supervisors=None) -> dict:
    """Label -> (named filter, options) of the filters run on the drive (``supervisors``:
    label -> (named filter, rule file) of further fuzzy designs tuned on simulation)."""
    from fuzzynav.filters.baselines import TUNED

    specs = {n: (n, {"params": str(params)} if n in TUNED else {}) for n in CAR_FILTERS}
    specs[SIM_FUZZY] = ("fakf", {"rules": [str(sim_rules)]})
    for label, (name, path) in (supervisors or {}).items():
        specs[label] = (name, {"rules": [str(path)]})
    if car_rules is not None:
        specs[CAR_FUZZY] = ("fakf", {"rules": [str(car_rules)]})
    return specs


def car_table(directory: Path, specs: dict, seeds) -> pd.DataFrame:
    """One row per filter and seed: the protocol's metrics of both feeds."""
    from fuzzynav.realdata.protocol import ProtocolSettings
    from fuzzynav.realdata.sources import SOURCES, resolve_mounting
    from fuzzynav.realdata.validate import validate

    rec = SOURCES["rtklib"].load(directory, mounting=resolve_mounting("rtklib-drive"))
    rows = []
    for label, (name, options) in specs.items():
        for seed in seeds:
            v = validate(rec, name, ProtocolSettings(), seed, options)
            m, out = v.runs["gnss"].metrics, v.runs["outages"].metrics
            rows.append({"scenario": "rtklib-drive", "seed": seed, "filter": label,
                         **{k: m[k] for k in CAR_METRICS},
                         "drift_h_rms_m": out["drift_h_rms_m"], "completed":
                         min(m["completed"], out["completed"])})
    return pd.DataFrame(rows)


def _save_systems(systems: dict, directory: Path, stem: str = "fuzzy_tuned") -> Path:
    """A tuned fuzzy design as a rule file (one controller: the GNSS one)."""
    from fuzzynav.fuzzy.io import save_fis

    if len(systems) != 1:
        raise ValueError(f"expected one tuned controller, got {sorted(systems)}")
    path = directory / f"{stem}.json"
    save_fis(next(iter(systems.values())), path)
    return path


def _drift_lines(df: pd.DataFrame, order) -> list:
    from fuzzynav.pages import scores as sr

    lines = ["| filter | horizontal RMS, GNSS throughout (m) | velocity RMS (m/s) | "
             "drift RMS over the outages (m) | runs completed |", "|---|---|---|---|---|"]
    for f in order:
        sub = df[df["filter"] == f]
        lines.append(f"| {f} | {sr.cell(sub['rms_pos_h_m'])} | {sr.cell(sub['rms_vel_mps'])} "
                     f"| {sr.cell(sub['drift_h_rms_m'])} | {int(sub['completed'].sum())}/"
                     f"{len(sub)} |")
    return lines


def _paired_lines(scores, scenario, fuzzies, ref) -> list:
    """A sentence per fuzzy controller against the best classical filter and ``ref``."""
    from fuzzynav.pages import scores as sr

    pool = scores[sr.is_classical(scores["filter"]) & ~scores["filter"].isin(fuzzies)]
    best = pool.groupby("filter")["score"].mean().idxmin()
    out = []
    for f in fuzzies:
        for other in dict.fromkeys((best, ref)):
            out.append("- " + sr.sentence(scenario, f"`{f}`", f"`{other}`",
                                          sr.paired(scores, scenario, f, other)))
    return out


def car_section(directory: Path, params: Path, systems: dict, car_rules, seeds,
                supervisors=None) -> tuple:
    """Markdown lines of the car drive and its rows (``supervisors``: label -> (named
    filter, systems) of further fuzzy designs)."""
    from fuzzynav.pages import scores as sr

    rules = Path(car_rules) if car_rules else CAR_RULES
    note = [] if rules.is_file() else [
        f"No controller tuned on the drive itself is judged here (`{rules.name}` absent): "
        "the one tuned on the first half of the drive (`studies/rtklib_split.toml`) is "
        "judged on the second half in docs/studies.md; this section runs the whole drive, "
        "so only controllers tuned on simulation are held out here.", ""]
    with tempfile.TemporaryDirectory() as tmp:
        sup = {label: (name, _save_systems(s, Path(tmp), label))
               for label, (name, s) in (supervisors or {}).items()}
        specs = _car_specs(params, _save_systems(systems, Path(tmp)), rules if rules.is_file()
                           else None, sup)
        df = car_table(directory, specs, seeds)
    scores = sr.scores_to(df, sr.REF, CAR_METRICS)
    fuzzies = [f for f in (SIM_FUZZY, *sup, CAR_FUZZY) if f in specs]
    order = [*fuzzies, *CAR_FILTERS]
    return [
        "### The car drive (`rtklib-drive`, consumer MEMS IMU, real)", "",
        f"Protocol of docs/validation.md (2 m noise per axis added to the fixes, 60-s "
        f"outages every 180 s, shipped mounting), noise seeds 0–{len(seeds) - 1}; every "
        "filter is run with what it learned on the *simulated* training runs. Score: the "
        "mean of the horizontal-position and velocity RMS ratios with GNSS throughout; the "
        "CI is over noise seeds of this one recording. There is no oracle on a recording "
        "(its true noise is unknown).", "", *note,
        "| filter | score vs `ekf-tuned` |", "|---|---|",
        *[f"| {f} | {sr.cell(scores[scores['filter'] == f]['score'])} |" for f in order], "",
        *_drift_lines(df, order), "", *_paired_lines(scores, "rtklib-drive", fuzzies, sr.REF),
        ""], df


def _held_out_trajectories(rules: Path) -> list:
    """The A-KIT trajectories a recording-trained rule file was judged on (its provenance)."""
    import json

    test = json.loads(rules.read_text()).get("provenance", {}).get("test", [])
    return [str(name).rpartition(":")[2] for name, _seed in test
            if str(name).startswith("akit:")]


def auv_section(directory: Path, auv_rules) -> tuple:
    """Markdown lines of the AUV runs (or the note why they are skipped), and their rows."""
    from fuzzynav.pages import scores as sr

    rules = Path(auv_rules) if auv_rules else AUV_RULES
    if not directory.is_dir():
        return [f"*The AUV recordings are not here ({directory}): section skipped.*", ""], None
    if not rules.is_file():
        return [f"*The AUV trajectories are not judged: no DVL controller tuned on "
                f"recordings (`{rules.name}` absent; paper 004's leave-trajectories-out study "
                "writes it). The classical filters on them: docs/paper004.md.*", ""], None
    from fuzzynav.realdata.akit import run_all
    from fuzzynav.realdata.loaders.akit_recording import load_akit

    held = _held_out_trajectories(rules)
    if not held:
        return [f"*The AUV trajectories are not judged: `{rules.name}` names no held-out "
                "A-KIT trajectory in its provenance.*", ""], None
    recs = load_akit(directory, ",".join(held))
    extra = [("apso", "apso", {"rules": [str(AUV_APSO)]})] if AUV_APSO.is_file() else []
    frames = []
    for label, name, opts in [*[(f, f, None) for f in AUV_FILTERS], *extra,
                              (AUV_FUZZY, "fakf", {"rules": [str(rules)]})]:
        df, _ = run_all(recs, name, opts)
        frames.append(df.assign(filter=label, scenario="akit"))
    df = pd.concat(frames)
    scores = sr.scores_to(df, "ekf", CAR_METRICS)
    return [f"### The AUV trajectories held out (A-KIT {', '.join(held)}, DVL-aided)", "",
            f"The controller (and `apso`) were tuned on the other A-KIT trajectories "
            f"(`{rules.name}`'s provenance); pairs are the held-out trajectories; score: mean "
            "of horizontal-position and velocity RMS ratios to the EKF with DVL. Both folds, "
            "per trajectory: docs/paper004.md.", "",
            "| filter | score vs `ekf` |", "|---|---|",
            *[f"| {f} | {sr.cell(scores[scores['filter'] == f]['score'])} |"
              for f in (AUV_FUZZY, *AUV_FILTERS, *[e[0] for e in extra])], "",
            *_paired_lines(scores, "akit", [AUV_FUZZY], "ekf"), ""], df


def recordings_section(args, params: Path, systems: dict, supervisors=None) -> tuple:
    """The page's "Held-out recordings" section and the rows it scored (or None);
    ``supervisors``: label -> (named filter, systems) of the fuzzy supervisors."""
    root = data_root(args.data)
    seeds = list(range(args.mc_recordings))
    lines = ["## Held-out recordings", "",
             "Real data, never seen in training (the controllers and the tuned constants "
             "were learned on simulated runs; a controller learned on recordings is judged "
             "when its rule file exists).", ""]
    car, car_df = car_section(root / "rtklib-drive", params, systems, args.car_rules, seeds,
                              supervisors) \
        if (root / "rtklib-drive").is_dir() else \
        ([f"*The car drive is not here ({root / 'rtklib-drive'}): section skipped. Set "
          "`FUZZYNAV_DATA` or pass `--data`.*", ""], None)
    auv, auv_df = auv_section(root / "akit", args.auv_rules)
    frames = [d for d in (car_df, auv_df) if d is not None]
    return lines + car + auv, (pd.concat(frames) if frames else None)


AUV_HEADING = "### The AUV trajectories held out"
AUV_END = "Every run's metrics:"


def splice_auv(page: str, auv_lines: list) -> str:
    """``page`` (docs/science.md) with its AUV subsection replaced by ``auv_lines``: from its
    heading up to the closing "Every run's metrics" line, the rest untouched."""
    a = page.index(AUV_HEADING)
    b = page.index(AUV_END, a)
    return page[:a] + "\n".join(auv_lines) + "\n" + page[b:]


def regenerate_auv(data: str | None = None, auv_rules: str | None = None,
                   root: Path = ROOT) -> None:
    """Rerun the AUV subsection of docs/science.md and its rows of
    docs/science_recordings.csv alone (the simulated sections need hours of tuning;
    ``fuzzynav docs regenerate science`` regenerates the whole page)."""
    from fuzzynav.fileio import write_atomic

    lines, df = auv_section(data_root(data) / "akit", auv_rules)
    page = root / "docs" / "science.md"
    text = splice_auv(page.read_text(), lines)
    write_atomic(page, lambda tmp: Path(tmp).write_text(text))
    csv = root / "docs" / "science_recordings.csv"
    if df is not None and csv.is_file():
        old = pd.read_csv(csv)
        # columns only the replaced rows had (an earlier loader's fields) go with them
        new = pd.concat([old[old["scenario"] != "akit"], df]).dropna(axis=1, how="all")
        write_atomic(csv, lambda tmp: new.to_csv(tmp, index=False))
