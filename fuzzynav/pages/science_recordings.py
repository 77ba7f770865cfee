"""The held-out recordings of ``docs/science.md``: the car drive and the AUV trajectories.

Called by :mod:`fuzzynav.pages.science` (the section "Held-out recordings"); every part
that lacks its data or its rules is skipped with a sentence on the page saying so.

* **Car drive** (``$FUZZYNAV_DATA/rtklib-drive``, ``--data`` of the script): the protocol of
  ``docs/validation.md`` (fixes with 2 m white noise per axis, 60-s outages every 180 s,
  the shipped mounting) on ``--mc`` noise seeds, each filter on the same noisy fixes of a
  seed.  Compared: the classical filters with the parameters tuned on the *simulated*
  training runs (``studies/paper000_baselines.json``), the paper's fuzzy rules (``fakf``),
  the fuzzy controller tuned on the same simulated runs (``fuzzy-tuned``: trained on
  simulation, judged on a real drive).  A controller tuned on the drive itself is never
  run on the whole drive (it would be judged on its training half).  Score per seed:
  the mean of the horizontal-position and velocity RMS ratios to ``ekf-tuned`` with GNSS
  throughout (a recording has no attitude truth); the outage drift is tabulated apart.
  The CI is over noise seeds of one recording, not over recordings.
* **The drive's second half** (:func:`split_section`): the fuzzy controller and the classical
  filters tuned on the first half with the same budget (``rules/rtklib_drive_tuned.json``,
  ``studies/rtklib_split_baselines.json``), on noise seeds 100+ of the held-out half
  (:mod:`fuzzynav.pages.science_splits`).
* **AUV** (``$FUZZYNAV_DATA/akit``, :func:`auv_section`): both A-KIT folds (1-4 -> 5-8 and
  5-8 -> 1-4), each with its fuzzy DVL controller and the classical filters tuned on its four
  training trajectories; the held-out trajectories are the pairs.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import pandas as pd

from fuzzynav.pages.common import REPO_ROOT as ROOT

__all__ = ["DATA_ENV", "SPLIT_SEED0", "CAR_FILTERS", "CAR_METRICS", "SIM_FUZZY", "data_root",
           "car_table", "car_section", "split_section", "auv_section", "tuning_rows",
           "splice_rows", "recordings_section", "AUV_HEADING", "AUV_END", "splice", "RERUN_MARK",
           "note_rerun", "SPLIT_HEADING", "PARTS", "regenerate_held_out"]

DATA_ENV = "FUZZYNAV_DATA"
#: the first noise seed on the car drive's held-out half (its training used seeds 0-2)
SPLIT_SEED0 = 100
CAR_FILTERS = ("ekf", "ekf-tuned", "als", "sage-husa", "sage-husa-tuned", "vb", "vb-tuned",
               "huber-tuned", "strong-tracking-tuned", "fakf")
CAR_METRICS = ("rms_pos_h_m", "rms_vel_mps")
SIM_FUZZY = "fuzzy-tuned"


def data_root(given=None) -> Path:
    """Where the recordings lie: ``given``, ``$FUZZYNAV_DATA`` or ``../shared/datasets``."""
    if given:
        return Path(given)
    return Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets"))


def _car_specs(params: Path, sim_rules: Path, supervisors=None) -> dict:
    """Label -> (named filter, options) of the filters run on the drive (``supervisors``:
    label -> (named filter, rule file) of further fuzzy designs tuned on simulation)."""
    from fuzzynav.filters.baselines import TUNED

    specs = {n: (n, {"params": str(params)} if n in TUNED else {}) for n in CAR_FILTERS}
    specs[SIM_FUZZY] = ("fakf", {"rules": [str(sim_rules)]})
    for label, (name, path) in (supervisors or {}).items():
        specs[label] = (name, {"rules": [str(path)]})
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


def car_section(directory: Path, params: Path, systems: dict, seeds,
                supervisors=None) -> tuple:
    """Markdown lines of the car drive and its rows (``supervisors``: label -> (named
    filter, systems) of further fuzzy designs)."""
    from fuzzynav.pages import scores as sr

    note = ["The controller tuned on the drive's first half is not run here (it would be "
            "judged on its own training half): the next subsection judges it on the second "
            "half.", ""]
    with tempfile.TemporaryDirectory() as tmp:
        sup = {label: (name, _save_systems(s, Path(tmp), label))
               for label, (name, s) in (supervisors or {}).items()}
        specs = _car_specs(params, _save_systems(systems, Path(tmp)), sup)
        df = car_table(directory, specs, seeds)
    scores = sr.scores_to(df, sr.REF, CAR_METRICS)
    fuzzies = [f for f in (SIM_FUZZY, *sup) if f in specs]
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


@contextlib.contextmanager
def _data_env(root: Path):
    """The studies read relative recording directories from ``$FUZZYNAV_DATA``: point it at
    the page's data root while they run, so ``--data`` holds for them too."""
    old = os.environ.get(DATA_ENV)
    os.environ[DATA_ENV] = str(root)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(DATA_ENV, None)
        else:
            os.environ[DATA_ENV] = old


def split_section(root: Path, seeds, cache=None) -> tuple:
    """Markdown lines of the car drive's held-out half (every filter tuned on the first
    half) and its rows, or the note why it is skipped."""
    from fuzzynav.pages import science_splits as ss

    sp = ss.CAR_SPLIT
    head = ["### The car drive's second half, every filter tuned on its first half", "",
            f"The fuzzy controller (`{sp.study}`, exported to `{sp.rules}`) and the classical "
            f"filters (`{Path(sp.params).with_suffix('.toml').as_posix()}` -> `{sp.params}`) "
            "were tuned on the first half of the drive (noise seeds 0–2 of the protocol's "
            "2 m fix noise), each with 100 TPE trials, the Wilcoxon pruner and the same "
            "objective; they are judged on the second half, which training never saw.", ""]
    if not (root / "rtklib-drive").is_dir():
        return head + [f"*The car drive is not here ({root / 'rtklib-drive'}): skipped.*",
                       ""], None
    note = ss.missing_note([sp])
    if sp.missing():
        return head + note + [""], None
    sp = sp.available()
    from fuzzynav.pages import science_split_tunings as st

    with _data_env(root):
        df = ss.split_frame(sp, cache, seeds)
        frames = st.split_frames(sp, df, st.N_TUNINGS, cache, seeds, ROOT)
    what = (f"noise seeds {seeds[0]}–{seeds[-1]} of the one held-out half: the spread of the "
            "noise added to its fixes, not of drives")
    tail = st.split_tunings_lines([sp], {sp.label: frames}, "noise seeds")
    return (head + note + ss.splits_lines([sp], {sp.label: df}, "noise seeds", what) + tail,
            tuning_rows({sp.label: frames}))


def auv_section(directory: Path, cache=None) -> tuple:
    """Markdown lines of both A-KIT folds (or the note why they are skipped), and their
    rows."""
    from fuzzynav.pages import science_splits as ss

    head = [f"{AUV_HEADING} (both folds, A-KIT 1–4 ↔ 5–8, DVL-aided)", "",
            "Each fold's fuzzy DVL controller (`studies/paper004_fuzzy.toml` / `_rev`, "
            "150 TPE trials) and classical filters (`studies/paper004_baselines.toml` / "
            "`_rev`, 150 TPE trials each, same pruner and objective) were tuned on four "
            "trajectories and are judged on the other four; `apso` is paper 004's PSO of the "
            "Q/R multipliers on the same four (150 evaluations, the same budget). Pairs are "
            "the held-out trajectories: with four pairs a 95 % CI is wide (Student t with 3 "
            "degrees of freedom, 3.18 standard errors), so only a large, consistent "
            "difference is a win or a loss. Per trajectory: docs/paper004.md.", ""]
    if not directory.is_dir():
        return head + [f"*The AUV recordings are not here ({directory}): skipped.*", ""], None
    folds = [f for f in ss.AKIT_FOLDS if not f.missing()]
    note = ss.missing_note(ss.AKIT_FOLDS)
    if not folds:
        return head + note + [""], None
    from fuzzynav.pages import science_split_tunings as st

    with _data_env(directory.parent):
        frames = {f.label: ss.split_frame(f, cache) for f in folds}
        tuned = {f.label: st.split_frames(f, frames[f.label], st.N_TUNINGS, cache)
                 for f in folds}
    lines = ss.splits_lines(folds, frames, "trajectories",
                            "the four held-out trajectories of each fold")
    lines += st.split_tunings_lines(folds, tuned, "trajectories")
    return head + note + lines, tuning_rows(tuned)


def tuning_rows(frames: dict) -> pd.DataFrame:
    """Every tuning's runs of some splits as one frame with a ``tuning`` column
    (``frames``: split label -> tuning -> runs, :func:`~fuzzynav.pages.
    science_split_tunings.split_frames`)."""
    return pd.concat([df.assign(tuning=k) for per in frames.values() for k, df in per.items()],
                     ignore_index=True)


def splice_rows(path: Path, rows: pd.DataFrame) -> pd.DataFrame:
    """The recordings CSV at ``path`` with the rows of ``rows``' scenarios replaced by
    ``rows`` (the other scenarios' rows kept; older files without ``tuning`` are rows of
    the first tuning), written atomically; returns what was written."""
    from fuzzynav.fileio import write_atomic

    old = pd.read_csv(path) if path.is_file() else pd.DataFrame()
    if not old.empty and "tuning" not in old:
        old = old.assign(tuning=0)
    keep = old[~old["scenario"].isin(set(rows["scenario"]))] if not old.empty else old
    out = pd.concat([keep, rows], ignore_index=True)
    write_atomic(path, lambda tmp: out.to_csv(tmp, index=False), suffix=".csv")
    return out


def recordings_section(args, params: Path, systems: dict, supervisors=None) -> tuple:
    """The page's "Held-out recordings" section and the rows it scored (or None);
    ``supervisors``: label -> (named filter, systems) of the fuzzy supervisors."""
    root = data_root(args.data)
    seeds = list(range(args.mc_recordings))
    lines = ["## Held-out recordings", "",
             "Real data. First the whole car drive, with every filter as tuned on the "
             "simulated training runs; then the drive's second half and the A-KIT "
             "trajectories, held out from studies that tuned the fuzzy controller and the "
             "classical filters alike on the other part of the same recordings.", ""]
    car, car_df = car_section(root / "rtklib-drive", params, systems, seeds, supervisors) \
        if (root / "rtklib-drive").is_dir() else \
        ([f"*The car drive is not here ({root / 'rtklib-drive'}): section skipped. Set "
          "`FUZZYNAV_DATA` or pass `--data`.*", ""], None)
    if car_df is not None:  # the simulated studies' first tuning
        car_df = car_df.assign(tuning=0)
    split, split_df = split_section(root, [SPLIT_SEED0 + k for k in seeds],
                                    getattr(args, "cache", None))
    auv, auv_df = auv_section(root / "akit", getattr(args, "cache", None))
    frames = [d for d in (car_df, split_df, auv_df) if d is not None]
    return lines + car + split + auv, (pd.concat(frames) if frames else None)


AUV_HEADING = "### The AUV trajectories held out"
AUV_END = "Every run's metrics:"


def splice(page: str, part: str, lines: list) -> str:
    """``page`` (docs/science.md) with its subsection ``part`` (a key of :data:`PARTS`)
    replaced by ``lines``: from the part's heading up to the next mark (the next part's
    heading, or the closing "Every run's metrics" line), the rest untouched.

    Raises
    ------
    FuzzynavError
        The page lacks the part's heading or the mark after it.
    """
    from fuzzynav.errors import FuzzynavError

    heading, end = PARTS[part]
    try:
        a = page.index(heading)
        b = page.index(end, a)
    except ValueError:
        raise FuzzynavError(f"docs/science.md: no {heading!r} followed by {end!r}: the "
                            f"{part!r} part cannot be spliced in (regenerate the whole "
                            "page)") from None
    return page[:a] + "\n".join(lines) + "\n" + page[b:]


RERUN_MARK = "*Rerun alone since (`fuzzynav docs regenerate science --only PART`):"


def note_rerun(page: str, part: str, date: str | None = None) -> str:
    """``page`` with ``part`` (and ``date``, default today) in the line that follows its
    "Generated by" line and lists the parts rerun alone since (added when absent; a
    part named again gets its new date; a page without that line is returned as it is)."""
    import datetime as _dt
    import re

    date = date or _dt.date.today().isoformat()
    lines = page.split("\n")
    gen = next((i for i, line in enumerate(lines) if line.startswith("Generated by")), None)
    if gen is None:
        return page
    have = lines[gen + 2] if len(lines) > gen + 2 and lines[gen + 2].startswith(RERUN_MARK) \
        else None
    done = dict(re.findall(r"`(\w+)` \((\d{4}-\d\d-\d\d)\)", have or ""))
    done[part] = date
    note = RERUN_MARK + " " + ", ".join(f"`{k}` ({v})" for k, v in done.items()) + ".*"
    if have is None:
        lines[gen + 1:gen + 1] = ["", note]
    else:
        lines[gen + 2] = note
    return "\n".join(lines)


SPLIT_HEADING = "### The car drive's second half, every filter tuned on its first half"
#: part -> (its heading, the mark that ends it) on docs/science.md
PARTS = {"split": (SPLIT_HEADING, AUV_HEADING), "auv": (AUV_HEADING, AUV_END)}


def regenerate_held_out(data: str | None = None, root: Path = ROOT,
                        mc_recordings: int = 5, parts=("split", "auv")) -> None:
    """Rerun the car drive's split and/or the AUV subsection of docs/science.md (with their
    tuning-variance tables) and splice them in, the rest of the page untouched; their rows
    (every tuning) replace theirs in docs/science_recordings.csv (:func:`splice_rows`)."""
    from fuzzynav.fileio import write_atomic

    droot = data_root(data)
    split, split_rows = split_section(droot, [SPLIT_SEED0 + k for k in range(mc_recordings)]) \
        if "split" in parts else (None, None)
    auv, auv_rows = auv_section(droot / "akit") if "auv" in parts else (None, None)
    # read the page only now: another splice may have rewritten it while these ran
    page = root / "docs" / "science.md"
    text = page.read_text()
    for part, lines in (("split", split), ("auv", auv)):
        if lines is not None:
            text = note_rerun(splice(text, part, lines), part)
    write_atomic(page, lambda tmp: Path(tmp).write_text(text))
    for rows in (split_rows, auv_rows):
        if rows is not None:
            splice_rows(root / "docs" / "science_recordings.csv", rows)
