"""The car drive's held-out half over several tunings (``docs/science.md``).

The fuzzy R-scaling controller and ``ekf-tuned`` (the best classical filter of the drive's
held-out half in the first tuning) are each tuned twice more on the first half, with other
sampler seeds and nothing else changed (``studies/rtklib_split_t1.toml``, ``_t2``;
``studies/rtklib_split_baselines_t1.toml``, ``_t2``).  Each tuning's paired differences on
the held-out noise seeds form one row of a tuning x seed table, and the pooled CI treats both
as crossed random factors (:func:`fuzzynav.metrics.crossed_ci`), so it covers what another
tuning would give.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CAR_TUNINGS", "DESIGN", "REF", "differences", "tunings_lines", "frames_of"]

#: (rule file, parameter file) of the further tunings (the first is the split's own)
CAR_TUNINGS = (("rules/rtklib_drive_tuned_t1.json", "studies/rtklib_split_baselines_t1.json"),
               ("rules/rtklib_drive_tuned_t2.json", "studies/rtklib_split_baselines_t2.json"))
DESIGN = "fuzzy-drive"
REF = "ekf-tuned"


def differences(frames, metrics) -> np.ndarray:
    """Tuning x seed table of score(:data:`DESIGN`) − score(:data:`REF`), the score the
    studies' objective against :data:`REF` of the same tuning (one frame per tuning, as
    :func:`fuzzynav.pages.science_splits.split_frame` gives).

    Raises
    ------
    ValueError
        The tunings were judged on different seeds.
    """
    from fuzzynav.pages import scores as sr

    rows, seeds = [], None
    for df in frames:
        sc = sr.scores_to(df[df["filter"].isin([DESIGN, REF])], REF, metrics)
        piv = sc.pivot_table(index="seed", columns="filter", values="score").sort_index()
        if seeds is not None and list(piv.index) != seeds:
            raise ValueError(f"tunings judged on different seeds: {seeds} and "
                             f"{list(piv.index)}")
        seeds = list(piv.index)
        rows.append((piv[DESIGN] - piv[REF]).to_numpy(float))
    return np.vstack(rows)


def tunings_lines(frames, metrics, unit: str) -> list:
    """Markdown: each tuning's mean difference (95 % CI over ``unit``) and the pooled one."""
    from fuzzynav.metrics import crossed_ci, mean_ci
    from fuzzynav.pages import scores as sr

    d = differences(frames, metrics)
    lines = [f"**Over {len(d)} tunings.** `{DESIGN}` and `{REF}` tuned {len(d)} times on the "
             "first half (sampler seeds 14, 114, 214; `studies/rtklib_split_t1.toml`, `_t2` "
             "and `rtklib_split_baselines_t1.toml`, `_t2` for the further two): the paired "
             f"difference `{DESIGN}` − `{REF}` per tuning (95 % CI over {unit}), then pooled "
             "with the tuning and the noise seed as crossed random factors:", "",
             "| tuning | difference (95 % CI) | verdict |", "|---|---|---|"]
    for i, row in enumerate(d):
        est = mean_ci(row)
        lines.append(f"| {i} | {est.mean:+.3f} [{est.lo:+.3f}, {est.hi:+.3f}] | "
                     f"{sr.verdict(est)} |")
    est = crossed_ci(d)
    lines += [f"| pooled | {est.mean:+.3f} [{est.lo:+.3f}, {est.hi:+.3f}] | "
              f"{sr.verdict(est)} |", ""]
    return lines


def frames_of(split, cache, seeds, root) -> list:
    """:func:`~fuzzynav.pages.science_splits.split_frame` of every further tuning of
    ``split`` whose files exist (an empty list when one is absent)."""
    from dataclasses import replace

    from fuzzynav.pages.science_splits import split_frame

    if not all((root / r).is_file() and (root / p).is_file() for r, p in CAR_TUNINGS):
        return []
    # only the two filters compared: the untuned ones do not depend on the tuning
    return [split_frame(replace(split, rules=r, params=p, supervisors=()), cache, seeds,
                        root, untuned=()) for r, p in CAR_TUNINGS]
