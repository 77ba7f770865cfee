"""Tuning variance on the pages: every tuned filter, fuzzy and classical, over several tunings.

A *tuning* is one run of a page's studies with one sampler seed, nothing else changed.  The
first is the shipped one; tuning ``k`` >= 1 lives in files named like the first with
``_t<k>`` before the suffix (:func:`tuning_file`: ``rules/paper003_rscale_tuned_pol.json``
-> ``rules/paper003_rscale_tuned_pol_t1.json``, ``studies/paper004_baselines.json`` ->
``studies/paper004_baselines_t1.json``), tuned by the study files named the same way
(``studies/paper004_baselines_t1.toml``, whose ``[study] seed`` is the tuning's).

The one helper for the car drive's split, the A-KIT folds and the paper pages: a page runs
each tuning's filters on the same held-out runs, scores them (one frame with columns
``scenario, seed, filter, score, tuning``) and calls :func:`tunings_lines`.  Each tuned
design is paired per test seed with the best equally tuned classical filter *of the same
tuning*; the table gives each tuning's paired difference (95 % CI over the seeds), the
pooled one with the tuning and the test seed as crossed random factors
(:func:`fuzzynav.metrics.crossed_ci`: it covers what another tuning would give), and the
spread between tunings and between test seeds (:func:`spread`).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav.pages.common import REPO_ROOT as ROOT

__all__ = ["tuning_file", "tuning_spec", "tunings_present", "differences", "spread",
           "best_on_training", "tunings_lines", "score_spread_lines", "split_of",
           "split_frames", "split_scores", "split_tunings_lines", "tunings_section",
           "N_TUNINGS", "provenance_score"]

TALLY = ("wins against", "draws with", "loses to")
#: the name of one pair, for the names of the pairs the pages use
ONE = {"seeds": "seed", "noise seeds": "noise seed", "trajectories": "trajectory"}


def tuning_file(path: str, k: int) -> str:
    """The file of tuning ``k`` beside ``path`` (the first tuning's): ``_t<k>`` before the
    suffix; ``k`` 0 is ``path`` itself."""
    if k == 0:
        return path
    p = Path(path)
    return p.with_name(f"{p.stem}_t{k}{p.suffix}").as_posix()


def tuning_spec(spec: str, k: int) -> str:
    """A filter spec ``NAME@A+B`` with each file replaced by tuning ``k``'s."""
    name, at, files = spec.partition("@")
    if not at:
        return spec
    return name + "@" + "+".join(tuning_file(f, k) for f in files.split("+"))


def tunings_present(files, n: int, root: Path = ROOT) -> list:
    """The tunings ``0 .. n-1`` of which every one of ``files`` (the first tuning's) exists
    under ``root``."""
    return [k for k in range(n)
            if all((Path(root) / tuning_file(f, k)).is_file() for f in files)]


def _best_of(scores, scenario, tuning, best, pool) -> str:
    if best is not None:
        return best[tuning]
    sub = scores[(scores["scenario"] == scenario) & (scores["tuning"] == tuning)
                 & scores["filter"].isin(pool)]
    if sub.empty:
        raise ValueError(f"no filter of {list(pool)} ran on {scenario!r} in tuning {tuning}")
    return sub.groupby("filter")["score"].mean().idxmin()


def differences(scores: pd.DataFrame, scenario: str, design: str, best=None,
                pool=None) -> tuple:
    """``(table, refs)``: tuning x test seed of ``score(design) - score(ref)`` on
    ``scenario``, ``ref`` the classical filter of the same tuning, and those refs.

    Parameters
    ----------
    scores : DataFrame
        ``scenario, seed, filter, score, tuning``.
    best : mapping, optional
        Tuning -> the classical filter compared with (chosen beforehand, e.g. on the
        training runs: :func:`best_on_training`).
    pool : sequence of str, optional
        With ``best`` None: per tuning, the filter of ``pool`` with the lowest mean score on
        ``scenario`` (a choice made on these runs, which favours the classical side).

    Raises
    ------
    ValueError
        Neither ``best`` nor ``pool``, a filter missing from a tuning, or tunings judged on
        different seeds.
    """
    if best is None and pool is None:
        raise ValueError("differences needs best (tuning -> filter) or pool")
    rows, refs, seeds = [], [], None
    for t in sorted(scores["tuning"].unique()):
        ref = _best_of(scores, scenario, t, best, pool)
        sub = scores[(scores["scenario"] == scenario) & (scores["tuning"] == t)]
        piv = sub.pivot_table(index="seed", columns="filter", values="score").sort_index()
        for f in (design, ref):
            if f not in piv:
                raise ValueError(f"{f!r} did not run on {scenario!r} in tuning {t}")
        if seeds is not None and list(piv.index) != seeds:
            raise ValueError(f"tunings judged on different seeds: {seeds} and "
                             f"{list(piv.index)}")
        seeds = list(piv.index)
        rows.append((piv[design] - piv[ref]).to_numpy(float))
        refs.append(ref)
    return np.vstack(rows), refs


def spread(table) -> tuple:
    """``(between tunings, between seeds)`` of a tuning x seed table: the standard
    deviation of the tunings' means, and the pooled standard deviation over seeds within a
    tuning (root of the mean within-tuning variance); NaN where there is one row / column."""
    x = np.asarray(table, float)
    between = float(np.std(x.mean(axis=1), ddof=1)) if x.shape[0] > 1 else float("nan")
    within = float(np.sqrt(np.mean(np.var(x, axis=1, ddof=1)))) if x.shape[1] > 1 \
        else float("nan")
    return between, within


def best_on_training(params_by_tuning: dict, pool: dict) -> dict:
    """Tuning -> the label of ``pool`` (label -> spec ``NAME@FILE``) whose filter has the
    lowest training score in that tuning's parameter file (``params_by_tuning``: tuning ->
    path), as :func:`fuzzynav.pages.scores.best_on_training` picks it."""
    from fuzzynav.pages import scores as sr

    by_spec = {v: k for k, v in pool.items()}
    return {t: by_spec[sr.best_on_training(path, list(pool.values()))[0]]
            for t, path in params_by_tuning.items()}


def tunings_lines(scores: pd.DataFrame, scenarios, designs, *, best=None, pool=None,
                  labels=None, unit: str = "seeds",
                  ref_head: str = "best classical per tuning") -> tuple:
    """Markdown rows (scenario x design) and the tally design -> {verdict: count} of the
    pooled verdicts (``ref_head``: the heading of the column naming the filter compared
    with).

    Each row: the classical filter compared with in each tuning, each tuning's paired
    difference (mean over test seeds, 95 % CI, verdict mark), the pooled difference over
    tunings and seeds (:func:`fuzzynav.metrics.crossed_ci`) and the spread between
    tunings and between seeds (:func:`spread`).  ``best``/``pool``: as in
    :func:`differences`; ``labels``: filter -> the name printed; ``unit``: the pairs'
    name (plural).
    """
    from fuzzynav.metrics import crossed_ci, mean_ci
    from fuzzynav.pages import scores as sr
    from fuzzynav.pages.science_sections import MARKS
    from fuzzynav.report import diff_cell as _ci

    labels = dict(labels or {})
    tunings = sorted(scores["tuning"].unique())
    lines = [f"| set | design | {ref_head} | "
             + " | ".join(f"tuning {t}" for t in tunings)
             + f" | pooled (tuning × {ONE.get(unit, unit)}) | SD between tunings | "
             f"SD between {unit} |",
             "|---|---|---|" + "---|" * (len(tunings) + 3)]
    tally = {d: dict.fromkeys(TALLY, 0) for d in designs}
    for s in scenarios:
        for d in designs:
            table, refs = differences(scores, s, d, best, pool)
            cells = [f"{_ci(e)} {MARKS[sr.verdict(e)]}".rstrip()
                     for e in (mean_ci(row) for row in table)]
            est = crossed_ci(table)
            v = sr.verdict(est)
            tally[d][v] = tally[d].get(v, 0) + 1
            names = list(dict.fromkeys(labels.get(r, r) for r in refs))
            between, within = spread(table)
            lines.append(f"| `{s}` | {labels.get(d, d)} | {', '.join(names)} | "
                         + " | ".join(cells) + f" | {_ci(est)} **{v}** | {between:.3f} | "
                         f"{within:.3f} |")
    return lines, tally


def score_spread_lines(scores: pd.DataFrame, filters, labels=None,
                       unit: str = "seeds") -> list:
    """Markdown: per filter, the mean score over every held-out run of each tuning, their
    range and standard deviation between tunings, and the pooled standard deviation of a
    run's score about its tuning's scenario mean (between test seeds)."""
    labels = dict(labels or {})
    tunings = sorted(scores["tuning"].unique())
    lines = ["| filter | " + " | ".join(f"tuning {t}" for t in tunings)
             + f" | min – max | SD between tunings | SD between {unit} |",
             "|---|" + "---|" * (len(tunings) + 3)]
    for f in filters:
        sub = scores[scores["filter"] == f]
        means = sub.groupby("tuning")["score"].mean().reindex(tunings)
        dev = sub["score"] - sub.groupby(["tuning", "scenario"])["score"].transform("mean")
        cells = sub.groupby(["tuning", "scenario"])["score"].count()
        dof = float((cells - 1).clip(lower=0).sum())
        within = float(np.sqrt((dev ** 2).sum() / dof)) if dof > 0 else float("nan")
        sd = float(np.std(means, ddof=1)) if len(tunings) > 1 else float("nan")
        lines.append(f"| {labels.get(f, f)} | " + " | ".join(f"{m:.3f}" for m in means)
                     + f" | {means.min():.3f} – {means.max():.3f} | {sd:.3f} | "
                     f"{within:.3f} |")
    return lines


def split_of(split, k: int):
    """The :class:`~fuzzynav.pages.science_splits.Split` of tuning ``k``: its rule and
    parameter files (and the supervisors' and paper 004's APSO) of that tuning."""
    if k == 0:
        return split
    return replace(split, rules=tuning_file(split.rules, k),
                   params=tuning_file(split.params, k),
                   apso=tuning_file(split.apso, k) if split.apso else None,
                   supervisors=tuple((label, name, tuning_file(rules, k))
                                     for label, name, rules in split.supervisors))


def split_frames(split, first: pd.DataFrame, n: int, cache=None, seeds=None,
                 root: Path = ROOT) -> dict:
    """Tuning -> :func:`~fuzzynav.pages.science_splits.split_frame` of every tuning of
    ``split`` whose files exist (``first``: tuning 0's, already run; the further ones run
    only their tuned filters and ``ekf``, the reference of :func:`split_tunings_lines`'
    spread table; the other untuned filters do not depend on the tuning)."""
    from fuzzynav.pages.science_splits import split_frame

    out = {0: first}
    for k in range(1, n):
        sp = split_of(split, k)
        if not sp.missing(root) and all((root / r).is_file() for _, _, r in sp.supervisors):
            out[k] = split_frame(sp, cache, seeds, root, untuned=("ekf",))
    return out


def split_scores(frames: dict, ref: str, metrics) -> pd.DataFrame:
    """The frames of :func:`split_frames` scored against ``ref`` of the same tuning, with
    a ``tuning`` column."""
    from fuzzynav.pages import scores as sr

    return pd.concat([sr.scores_to(df, ref, metrics).assign(tuning=k)
                      for k, df in frames.items()], ignore_index=True)


#: tunings looked for on the pages (the first and two further ones)
N_TUNINGS = 3


def sampler_seeds(study: str, tunings, root: Path = ROOT) -> list:
    """The sampler seed of each tuning's study file (``[study] seed``, or an alignment
    study's ``sampler_seed``)."""
    import tomllib

    out = []
    for k in tunings:
        doc = tomllib.loads((Path(root) / tuning_file(study, k)).read_text())
        out.append(doc.get("study", {}).get("seed", doc.get("sampler_seed")))
    return out


def seeds_text(studies, tunings, root: Path = ROOT) -> str:
    """``"`a.toml`, `b.toml`: sampler seeds 0, 100, 200"`` (the first study's seeds; the
    others' are checked to be the same)."""
    seeds = [sampler_seeds(s, tunings, root) for s in studies]
    if any(x != seeds[0] for x in seeds):
        raise ValueError(f"studies {list(studies)} tuned with other seeds: {seeds}")
    return (", ".join(f"`{s}`" for s in studies) + ": sampler seeds "
            + ", ".join(map(str, seeds[0])))


def split_tunings_lines(splits, frames: dict, unit: str, root: Path = ROOT, designs=None,
                        design_text: str = "Each fuzzy design", studies=None) -> list:
    """Markdown of some splits over their tunings (``frames``: split label -> tuning ->
    frame, :func:`split_frames`), or a note that the further tunings are absent.
    ``designs``: the filters judged against the best equally tuned classical filter (by
    default the splits' fuzzy designs; e.g. ``["apso"]``), named ``design_text``;
    ``studies``: the study files whose sampler seeds are cited (default each split's)."""
    import json

    from fuzzynav.pages.science_splits import SPLIT_METRICS

    ks = sorted(set.intersection(*(set(f) for f in frames.values()))) if frames else []
    if len(ks) < 2:
        need = [f for sp in splits for f in split_of(sp, 1).files()[1:]]
        return ["*Further tunings not judged: " + ", ".join(f"`{f}`" for f in need)
                + " (and `_t2`) absent.*", ""]
    n = len(ks)

    def scored(ref):
        return pd.concat([split_scores({k: frames[sp.label][k] for k in ks}, ref,
                                       SPLIT_METRICS) for sp in splits], ignore_index=True)

    scores, plain = scored("ekf-tuned"), scored("ekf")
    pool = list(json.loads((Path(root) / splits[0].params).read_text())["filters"])
    designs = list(designs or dict.fromkeys(d for sp in splits for d in sp.designs()))
    studies = "; ".join(seeds_text([f], ks, root)
                        for f in (studies or [sp.study for sp in splits]))
    train = {}
    for sp in splits:  # filter -> training score per tuning (with the set's name if several)
        train.update({(f if len(splits) == 1 else f"{f} (`{sp.label}`)"): v
                      for f, v in _split_training(sp, ks, root).items()})
    intro = (f"**Over {n} tunings.** Every tuned filter here, fuzzy and classical, was tuned "
             f"{n} times on the same training part with the same budget, nothing changed but "
             f"the sampler seed: {studies}; the further tunings' study files and outputs "
             "carry `_t1`, `_t2` (e.g. `" + tuning_file(splits[0].params, 1) + "`"
             + ("; each supervisor is warm-started at its parent of the same tuning"
                if any(sp.supervisors for sp in splits) else "") + f"). {design_text} "
             "against the best equally tuned classical filter of the same tuning (lowest "
             "mean score on these held-out runs, which favours it)")
    return tunings_section(scores, [sp.label for sp in splits], designs, intro=intro,
                           unit=unit, pool=pool, plain=plain,
                           plain_ref="against the untuned `ekf`, the same in every tuning",
                           spread_filters=[*designs, *pool], train=train)


def _split_training(split, ks, root: Path) -> dict:
    """Filter -> its training score in each tuning ``ks`` of ``split``."""
    import json

    sps = [split_of(split, k) for k in ks]
    out = {sps[0].fuzzy: [provenance_score(Path(root) / sp.rules) for sp in sps]}
    for i, (label, _, _) in enumerate(sps[0].supervisors):
        out[label] = [provenance_score(Path(root) / sp.supervisors[i][2]) for sp in sps]
    docs = [json.loads((Path(root) / sp.params).read_text())["train_score"] for sp in sps]
    out.update({f: [d[f] for d in docs] for f in docs[0]})
    if split.apso:  # paper 004's APSO: its own study and objective (position only)
        out["apso"] = [json.loads((Path(root) / sp.apso).read_text())["train_score"]["apso"]
                       for sp in sps]
    return out


def tunings_section(scores, scenarios, designs, *, intro: str, unit: str, best=None,
                    pool=None, plain=None, plain_ref: str = "", spread_filters=(),
                    labels=None, train=None) -> list:
    """The markdown of a page's tuning variance: ``intro`` (who was tuned, how, against
    what; completed by the sentence on the pairs), the table of :func:`tunings_lines`, a
    sentence per design with its pooled tally, the training scores per tuning (``train``:
    label -> list of scores, tuning order) and the spread of each filter's own score
    (:func:`score_spread_lines` on ``plain``: the runs scored against ``plain_ref``, a
    filter that is the same in every tuning).  ``unit`` names the pairs (plural)."""
    labels = dict(labels or {})
    rows, tally = tunings_lines(scores, scenarios, designs, best=best, pool=pool,
                                labels=labels, unit=unit)
    one = ONE.get(unit, unit)
    out = [intro + f", paired per {one}: each tuning's difference design − best (95 % CI "
           f"over {unit}; negative favours the design), then pooled with the tuning and the "
           f"{one} as crossed random factors (two-way random-effects model, Satterthwaite "
           "degrees of freedom: the CI covers another tuning, not only other "
           f"{unit}), and the spread of the paired difference between tunings and between "
           f"{unit}:", "", *rows, ""]
    out += [f"- {labels.get(d, f'`{d}`')} pooled over the tunings (wins / draws / losses "
            f"of the {len(scenarios)} set(s)): {t['wins against']} / {t['draws with']} / "
            f"{t['loses to']}." for d, t in tally.items()]
    if train:
        n = len(next(iter(train.values())))
        out += ["", "Training score per tuning (the objective on the training runs, as the "
                "studies report it):", "",
                "| filter | " + " | ".join(f"tuning {k}" for k in range(n))
                + " | SD between tunings |", "|---|" + "---|" * (n + 1)]
        out += [f"| {labels.get(f, f)} | " + " | ".join(f"{v:.3f}" for v in vals)
                + f" | {np.std(vals, ddof=1):.3f} |" for f, vals in train.items()]
    if plain is not None:
        out += ["", f"Score of each tuned filter per tuning ({plain_ref}), mean over "
                f"every held-out run here, its spread between tunings and between {unit}:",
                "", *score_spread_lines(plain, spread_filters, labels, unit)]
    return out + [""]


def provenance_score(path) -> float:
    """The training score a tuned rule file's study gave it (``provenance.objective.value``).

    Raises
    ------
    InputFileError
        The file has no such number.
    """
    import json

    from fuzzynav.errors import InputFileError

    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    value = ((doc.get("provenance") or {}).get("objective") or {}).get("value")
    if not isinstance(value, (int, float)):
        raise InputFileError(path, "$.provenance.objective.value", "missing: not a study's "
                             "export, so its training score is unknown")
    return float(value)
