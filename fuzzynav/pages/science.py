"""Regenerate ``docs/science.md``: the fuzzy designs against equally tuned baselines.

Run from the repository root (``[studies]`` extras installed)::

    fuzzynav docs regenerate science

1. tunes, once per tuning (sampler) seed (:mod:`fuzzynav.pages.science_tuning`), the
   classical baselines of ``studies/paper000_baselines.toml``, the fuzzy R-scaling
   controller of ``studies/paper000_fair.toml`` and the three fuzzy supervisors
   (``studies/paper000_fuzzy_*.toml``, warm-started from that tuning's tuned parents), each
   with the study files' budget; the first tuning's baselines are written to
   ``studies/paper000_baselines.json`` and its supervisors to
   ``rules/supervisor_*_tuned.json`` (the files the named ``-tuned`` filters read);
2. runs every filter of every tuning on every held-out run
   (:mod:`fuzzynav.pages.science_eval`) and writes, per scenario (never pooled): the
   weighted RMS ratio to the tuned constant-noise EKF (``ekf-tuned``) and to the oracle
   (``ekf-true``), and each fuzzy design's paired difference against the best classical
   baseline of that scenario, with 95 % CIs; the tuning variance
   (:mod:`fuzzynav.pages.science_sections`);
3. continues the first tuning's studies of the best fuzzy design and the best classical
   filter to ``curve_trials`` and draws the budget curves (held-out and training score of
   the best of the first n trials);
4. runs the held-out recordings (:mod:`fuzzynav.pages.science_recordings`).

Journals go to ``work`` (default: a temporary directory; an existing journal is resumed,
not re-tuned), simulations to the context's cache. :func:`build`'s ``quick`` is a smoke run.
"""
from __future__ import annotations

import datetime as _dt
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pandas as pd

from fuzzynav.fileio import write_atomic
from fuzzynav.pages.common import REPO_ROOT as ROOT
from fuzzynav.pages.common import machine
from fuzzynav.pages import science_sections as sec
from fuzzynav.pages import scores as sr
from fuzzynav.pages.science_eval import curve_points, held_out_runs
from fuzzynav.pages.science_recordings import recordings_section
from fuzzynav.pages.science_tuning import (SUPERVISOR_STUDIES, best_of_first,
                                           fuzzy_systems_at, tune_seed)
from fuzzynav.pages.scores import (
    FUZZY,
    ORACLE,
    REF,
    best_classical,
    comparison_lines,
    is_classical,
    paired,
    ratio_table,
    scores_to,
    verdict,
)

__all__ = ["DESIGNS", "params_lines", "summary_lines", "page_text", "closing_lines",
           "design_table", "cpu_minutes", "build", "regenerate_parts"]

DESIGNS = (FUZZY, *SUPERVISOR_STUDIES)


# -- the page ----------------------------------------------------------------------------------
def params_lines(params: Path) -> list:
    import json

    doc = json.loads(params.read_text())
    from fuzzynav.tuning.baseline_config import bound_hits

    lines = ["| filter | training score (ratio to ekf) | parameters |", "|---|---|---|"]
    hits = []
    for name, p in doc["filters"].items():
        ends = bound_hits(name, p, doc=doc)
        vals = ", ".join(f"{k} = {v:.3g}" + (f" (at the {ends[k]} end)" if k in ends else "")
                         for k, v in p.items())
        lines.append(f"| {name} | {doc['train_score'][name]:.3f} | {vals} |")
        hits += [f"{name}'s {k}" for k in ends]
    if hits:
        lines += ["", f"At the end of its search range (within 1 %): {', '.join(hits)}. The "
                  "best value may lie beyond what the study searched "
                  "(`fuzzynav/tuning/baseline_config.py`, `SPACES`), so these filters could "
                  "do better than shown here."]
    return lines


def summary_lines(scores, per_tuning: dict, scenarios, pooled_wins=None) -> list:
    """The verdict of the goal (a design beating the best equally tuned classical filter,
    paired 95 % CI excluding zero, on at least 4 of the held-out sets), per design and
    per tuning, and pooled over tunings (``pooled_wins``: design -> wins,
    :func:`~fuzzynav.pages.science_sections.pooled_lines`)."""
    n, need = len(scenarios), min(4, len(scenarios))
    lines = []
    for d in DESIGNS:
        wins = [sec.design_tally(per_tuning[s], scenarios, d)["wins against"]
                for s in per_tuning]
        t = sec.design_tally(scores, scenarios, d)
        lines.append(f"- `{d}` wins {t['wins against']}, draws {t['draws with']} and loses "
                     f"{t['loses to']} of {n} held-out sets against the best classical "
                     f"filter of each (first tuning); wins per tuning: "
                     f"{', '.join(map(str, wins))}" + (
                         f"; pooled over tunings (tuning seed a random factor): "
                         f"{pooled_wins[d]}" if pooled_wins else "") + ".")
    reached = [d for d in DESIGNS
               if all(sec.design_tally(per_tuning[s], scenarios, d)["wins against"] >= need
                      for s in per_tuning)]
    head = (f"**The goal (wins on at least {need} of {n} held-out sets) is reached by "
            f"{', '.join(f'`{d}`' for d in reached)} in every tuning.**" if reached else
            f"**No fuzzy design reaches the goal (wins on at least {need} of {n} held-out "
            "sets against the best equally tuned classical filter) in every tuning.**")
    return [head, "", *lines]


def page_text(ctx: dict, scores_ref, scores_oracle, scenarios) -> str:
    order = [*DESIGNS, *[f for f in ctx["filters"] if f not in DESIGNS]]
    best = ctx["best_design"]
    rows, text, _ = comparison_lines(scores_ref, scenarios, best)
    lines = [
        "# Science: fuzzy designs against equally tuned baselines", "",
        f"Generated by `{ctx['command']}` ({ctx['machine']}); "
        f"{ctx['minutes']:.1f} min wall time, {ctx['cpu']:.1f} min CPU" +
        ("; some studies were resumed from finished journals, so these times do not cover "
         "all of their tuning" if ctx["resumed"] else "") +
        ". Rerun it to refresh every number on this page." + (
            " **A --quick smoke run: too few trials and seeds to conclude anything.**"
            if ctx["quick"] else ""),
        "", "## What was run", "",
        f"- **Budget:** {ctx['trials']} TPE trials per study (the study files' budget) for "
        "each fuzzy design and for *each* tuned baseline "
        "(`studies/paper000_baselines.toml`, one Optuna study each, same sampler, pruner, "
        f"objective and training runs); ALS is estimated, not searched; {ctx['workers']} "
        "workers.",
        f"- **Tunings:** every tuned filter is tuned {len(ctx['tuning_seeds'])} times, with "
        f"sampler seeds {', '.join(map(str, ctx['tuning_seeds']))}; the tables below are "
        "the first tuning's, the section *Tuning variance* compares the tunings.",
        "- **Fuzzy designs:** `fuzzy-tuned`, the R-scaling controller (DoM → R factor, "
        "`studies/paper000_fair.toml`); and three *supervisors* that set a classical "
        "filter's constant per epoch from the GNSS innovations' ROR: `fuzzy-sage-husa-tuned` "
        "(Sage–Husa's b), `fuzzy-vb-tuned` (VB's ρ), `fuzzy-huber-tuned` (Huber's γ), each "
        "supervising its parent *as tuned in the same tuning* and warm-started at it (the "
        "study's first trial is the parent: docs/studies.md, *Warm start*).",
        f"- **Training runs:** {ctx['train']}.",
        f"- **Held-out runs:** {len(scenarios)} scenarios × {ctx['n_seeds']} seeds "
        "(seeds 100+, never trained on); three are on the training trajectory with other "
        "mismatch, four on routes never trained on (`-alt`, `-route-north`, `-route-urban`, "
        "`-route-spiral`, each with its own mismatch pattern: see `paper000_fair.toml`).",
        "- **Score:** per run, the mean over position, velocity and attitude of the RMS "
        "error ratio to a reference filter on the same data and initial error (1 = as good, "
        "lower is better); mean ± 95 % CI (Student t) over the seeds of one scenario. "
        "Scenarios are never pooled.",
        "- **Best classical baseline:** per scenario, the non-fuzzy, non-oracle filter with "
        "the lowest mean score there (chosen on the held-out data itself, which favours the "
        "baseline: a fuzzy design must beat the best one in hindsight).",
        f"- **Win / loss:** the paired 95 % CI excludes zero *and* the mean difference is at "
        f"least {sr.MIN_EFFECT} ({100 * sr.MIN_EFFECT:g} % of the reference's error); anything less is a draw "
        "(a supervisor that stays at its parent differs by ~1e-5 with an equally narrow CI).",
        "", "## Tuned parameters (first tuning)", "", *params_lines(ctx["params"]), "",
        *ctx["design_table"], "",
        "## Ratio to the tuned constant-noise EKF (`ekf-tuned`)", "",
        *ratio_table(scores_ref, order, scenarios), "",
        "## Ratio to the oracle (`ekf-true`, told the true noise of every epoch)", "",
        *ratio_table(scores_oracle, order, scenarios), "",
        "## The fuzzy designs against the best classical baseline", "",
        "Paired per seed (same data, same initial error); negative favours the fuzzy "
        "design; difference of the score relative to `ekf-tuned` [95 % CI].", "",
        *sec.designs_lines(scores_ref, scenarios, DESIGNS), "",
        f"The design with the lowest mean held-out score, `{best}`, set by set:", "",
        *rows, "", *text, "",
        "## Tuning variance", "", *ctx["variance"], "",
        "## Budget curves", "", *ctx["budget"], "",
        "## In short", "", *ctx["summary"], "",
        *closing_lines(scores_ref, scenarios, ctx["params"]), "",
        *ctx["recordings"],
        "Every run's metrics: [science_runs.csv](science_runs.csv) (column `tuning_seed`), "
        "the budget curves' points [science_budget.csv](science_budget.csv)"
        + (", on the recordings [science_recordings.csv](science_recordings.csv)."
           if ctx["recording_rows"] else "."),
    ]
    return "\n".join(lines) + "\n"


def closing_lines(scores: pd.DataFrame, scenarios, params: Path) -> list:
    """What the numbers do and do not say (facts read from the results and parameters)."""
    import json

    wins_ref = {d: [s for s in scenarios if verdict(paired(scores, s, d, REF)) == "wins against"]
                for d in DESIGNS}
    st = json.loads(params.read_text())["filters"].get("strong-tracking-tuned", {})
    lines = [
        "What the numbers do and do not say:", "",
        "- The fuzzy designs adapt only the GNSS (their rule files are bound to the "
        "receiver; a supervisor runs its parent with the parent's tuned constant on the "
        "other sensors); Sage–Husa, VB, Huber and strong tracking adapt every sensor, the "
        "polarization compass included — which matters on `paper000-heavy` (heavy-tailed "
        "compass errors).",
    ]
    if st and st.get("lam_max", 2.0) < 1.05:
        lines.append(f"- The tuned strong tracking filter learned to switch itself off (cap "
                     f"λ ≤ {st['lam_max']:.3g}): on these runs inflating P does not pay.")
    lines.append("- Against the tuned constant-noise EKF: " + "; ".join(
        f"`{d}` wins on {len(w)} of {len(scenarios)}" for d, w in wins_ref.items()) + ".")
    return lines


def design_table(tunings, trials) -> list:
    """Each fuzzy design's training score and, for a supervisor, its warm-start trial's."""
    t0 = tunings[0]
    lines = ["| fuzzy design (first tuning) | training score | first (warm-start) trial |",
             "|---|---|---|"]
    for label, (cfg, study) in t0.fuzzy.items():
        _, train = fuzzy_systems_at(cfg, study, trials)
        first = study.trials[0] if study.trials else None
        warm = (f"{first.value:.3f} (the tuned parent)" if first is not None
                and first.user_attrs.get("warm_start") and first.value is not None else "—")
        lines.append(f"| `{label}` | {train:.3f} | {warm} |")
    return lines


def cpu_minutes() -> float:
    """CPU time of this process and its finished children (study workers) [min]."""
    import resource

    use = [resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
    return sum(u.ru_utime + u.ru_stime for u in use) / 60.0


def _ship(tunings, trials, page_dir: Path, to_docs: bool) -> Path:
    """The first tuning's baselines to ``studies/paper000_baselines.json`` and its
    supervisors to ``rules/supervisor_*_tuned.json`` (docs page), or beside the page."""
    import shutil

    from fuzzynav.tuning.export import choose_trial, export_rules

    t0 = tunings[0]
    params = (ROOT / "studies" if to_docs else page_dir) / "paper000_baselines.json"
    shutil.copyfile(t0.params, params)
    for label, (cfg, study) in t0.fuzzy.items():
        if label in SUPERVISOR_STUDIES:
            name = SUPERVISOR_STUDIES[label].stem.replace("paper000_fuzzy_", "supervisor_")
            out = (ROOT / "rules" if to_docs else page_dir) / f"{name}_tuned.json"
            export_rules(cfg, study, out, choose_trial(best_of_first(study, trials),
                                                       cfg).number)
    return params


def _best(scores, names) -> str:
    """The filter of ``names`` with the lowest mean score over every run."""
    sub = scores[scores["filter"].isin(names)]
    return sub.groupby("filter")["score"].mean().idxmin()


def build(page_ctx, trials: int = 300, workers: int = 2, work: str | None = None,
          seeds: int | None = None, mc_recordings: int = 5, quick: bool = False,
          recordings: bool = True, tunings: int = 3, curve_trials: int = 1000,
          budgets: tuple = (30, 100, 300, 1000)) -> str:
    """The whole of docs/science.md; writes ``science_runs.csv``, ``science_budget.csv``
    (and ``science_recordings.csv``) beside the page.

    ``trials`` per study, ``workers`` per study, ``work`` the journals' directory,
    ``seeds`` held-out seeds per simulated scenario (None: all of the study),
    ``mc_recordings`` noise seeds on the drive, ``quick`` a smoke run, ``recordings`` False
    skips the recordings section (its recording-tuned files: :mod:`fuzzynav.pages.science_splits`);
    ``tunings`` sampler seeds per tuned filter; ``curve_trials`` the budget curves' longest
    study and ``budgets`` their points.
    """
    if quick:
        trials, seeds, mc_recordings, tunings = min(trials, 4), 2, 1, 1
        curve_trials, budgets = 2 * min(trials, 4), (2, min(trials, 4), 2 * min(trials, 4))
    page_dir = page_ctx.fig_dir.parent
    to_docs = page_dir.resolve() == (page_ctx.root / "docs").resolve()
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(work or tmp)
        work.mkdir(parents=True, exist_ok=True)
        resumed = any(work.glob("*.journal"))
        cache = str(page_ctx.cache)
        tuned = [tune_seed(s, trials, workers, work, cache) for s in range(tunings)]
        cfg = tuned[0].fuzzy[FUZZY][0]
        test = cfg.test
        if seeds:
            keep = sorted({d for _, d in test})[:seeds]
            test = tuple(r for r in test if r[1] in keep)
        df = held_out_runs(tuned, test, cache, trials)
        per_tuning = {t.seed: scores_to(df[df["tuning_seed"] == t.seed], "ekf")
                      for t in tuned}
        first = df[df["tuning_seed"] == tuned[0].seed]
        scores_ref = scores_to(first, REF)
        best_design = _best(per_tuning[tuned[0].seed], DESIGNS)
        ekf_scores = per_tuning[tuned[0].seed]
        best_classic = _best(ekf_scores[is_classical(ekf_scores["filter"])
                                        & ekf_scores["filter"].str.endswith("-tuned")],
                             ekf_scores["filter"].unique())
        curve = {best_design: curve_trials, best_classic: curve_trials}
        tuned[0] = tune_seed(tuned[0].seed, trials, workers, work, cache, curve)
        points = curve_points(tuned, list(curve), budgets, test, cache)
        params = _ship(tuned, trials, page_dir, to_docs)
        design_rows = design_table(tuned, trials)
        sup = {label: (tuned[0].fuzzy[label][0].filter,
                       fuzzy_systems_at(*tuned[0].fuzzy[label], trials)[0])
               for label in SUPERVISOR_STUDIES}
        systems = fuzzy_systems_at(*tuned[0].fuzzy[FUZZY], trials)[0]
        pooled, pooled_wins = sec.pooled_lines(per_tuning, list(dict.fromkeys(
            s for s, _ in test)), DESIGNS)
    opts = SimpleNamespace(data=str(page_ctx.data_dir), mc_recordings=mc_recordings,
                           cache=str(page_ctx.cache))
    recs, rec_rows = recordings_section(opts, params, systems, sup) if recordings else (
        ["## Held-out recordings", "", "*Skipped (--no-recordings).*", ""], None)
    scenarios = list(dict.fromkeys(s for s, _ in test))
    fig = "science_budget.png"
    ctx = dict(date=_dt.date.today().isoformat(), machine=machine(), trials=trials,
               workers=workers, minutes=(time.time() - t0) / 60.0, params=params,
               train=", ".join(f"`{s}` seed {d}" for s, d in cfg.train),
               n_seeds=len({d for _, d in test}), tuning_seeds=[t.seed for t in tuned],
               filters=list(dict.fromkeys(first["filter"])), cpu=cpu_minutes(),
               resumed=resumed, recordings=recs, recording_rows=rec_rows is not None,
               quick=quick, command=page_ctx.command, best_design=best_design,
               design_table=design_rows,
               variance=[*sec.variance_lines(per_tuning, DESIGNS, _tuned_classical(first),
                                             scenarios), "", *pooled],
               budget=[f"The first tuning's studies of the fuzzy design and the tuned "
                       f"classical filter with the lowest mean held-out score (`{best_design}`"
                       f", `{best_classic}`) are continued to {curve_trials} trials; each "
                       "point is the best of a study's first n trials (what a budget of n "
                       "would have returned), scored on every held-out run against the EKF; "
                       "the other tunings give the points up to their budget.", "",
                       *sec.budget_lines(points, page_ctx.fig_dir / fig, fig), "",
                       *sec.budget_sentences(points)],
               summary=summary_lines(scores_ref, {k: scores_to(df[df["tuning_seed"] == k],
                                                               REF) for k in per_tuning},
                                     scenarios, pooled_wins))
    for name, frame in (("science_runs.csv", df), ("science_budget.csv", points),
                        ("science_recordings.csv", rec_rows)):
        if frame is not None:
            write_atomic(page_dir / name, lambda tmp, f=frame: f.to_csv(tmp, index=False),
                         suffix=".csv")
    return page_text(ctx, scores_ref, scores_to(first, ORACLE), scenarios)


def _tuned_classical(df) -> list:
    names = list(dict.fromkeys(df["filter"]))
    return [n for n in names if n.endswith("-tuned") and not n.startswith("fuzzy")] + (
        ["als"] if "als" in names else [])


def regenerate_parts(parts, data_dir) -> None:
    """``fuzzynav docs regenerate science --only PART``: rerun the recordings parts
    ``parts`` (``split``, ``auv``) and splice them in
    (:func:`fuzzynav.pages.science_recordings.regenerate_held_out`)."""
    from fuzzynav.pages.science_recordings import regenerate_held_out

    regenerate_held_out(str(data_dir), parts=tuple(parts))
