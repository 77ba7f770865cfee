"""Figures: navigation error curves and adaptation factors over time (matplotlib).

Functions return the matplotlib Figure; :func:`save` writes it atomically.  matplotlib picks
its headless Agg backend by itself when there is no display (and Jupyter's inline backend in
notebooks), so nothing is forced here.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from fuzzynav.fileio import write_atomic

__all__ = ["error_curves", "adaptation_curves", "membership_functions", "save"]

_AXES = ("east", "north", "up")
_STYLES = ("-", "--", "-.", ":")


def error_curves(errors: dict, title: str = "", segments=()) -> plt.Figure:
    """Position, velocity and attitude errors of one or more filters against time.

    Parameters
    ----------
    errors : dict
        Label -> :class:`fuzzynav.metrics.NavErrors`.
    segments : sequence of (start_s, end_s, label), optional
        Motion segments to mark: every other one shaded in each panel, and each labelled
        at the top of the first row (``fuzzynav run --segments --plot DIR``).
    """
    fig, axs = plt.subplots(3, 3, figsize=(13, 8), sharex=True)
    for j, (label, err) in enumerate(errors.items()):
        ls = _STYLES[j % len(_STYLES)]
        for i in range(3):
            axs[0, i].plot(err.time_s, err.pos_m[:, i], ls, lw=0.9, label=label)
            axs[1, i].plot(err.time_s, err.vel_mps[:, i], ls, lw=0.9, label=label)
            axs[2, i].plot(err.time_s, np.rad2deg(err.att_rad[:, i]), ls, lw=0.9, label=label)
    for i, ax in enumerate(_AXES):
        axs[0, i].set_title(f"{ax} position error (m)")
        axs[1, i].set_title(f"{ax} velocity error (m/s)")
    for i, nm in enumerate(("pitch", "roll", "heading")):
        axs[2, i].set_title(f"{nm} error (deg)")
        axs[2, i].set_xlabel("time (s)")
    for ax in axs.flat:
        ax.grid(alpha=0.3)
        for t0, t1, _ in list(segments)[1::2]:
            ax.axvspan(t0, t1, color="0.85", alpha=0.5, lw=0)
    for ax in axs[0]:
        for t0, t1, label in segments:
            ax.text(0.5 * (t0 + t1), 1.0, label, transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=6, clip_on=True)
    axs[0, 0].legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def adaptation_curves(series: dict, title: str = "") -> plt.Figure:
    """Adaptation diagnostics (alpha, DoM, R scale, ...) against time, one panel each.

    Parameters
    ----------
    series : dict
        Label -> ``(time_s, values)``; each gets its own panel (their scales differ by
        orders of magnitude: alpha near 1, DoM down to -100, R factors up to 1000).
    """
    n = max(len(series), 1)
    fig, axs = plt.subplots(n, 1, figsize=(9, 1.6 * n + 0.8), sharex=True, squeeze=False)
    for ax, (label, (t, v)) in zip(axs[:, 0], series.items()):
        ax.plot(t, v, lw=0.9)
        ax.set_ylabel(label, rotation=0, ha="right", va="center", fontsize=8)
        ax.grid(alpha=0.3)
    axs[-1, 0].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def membership_functions(fis, title: str = "", n_points: int = 400) -> plt.Figure:
    """The terms of every input and output variable of a fuzzy system, one panel each."""
    from fuzzynav.fuzzy.membership import evaluate_mf

    variables = [v for v in list(fis.inputs) + list(fis.outputs)
                 if all(t.mf not in ("constant", "linear") for t in v.terms)]
    fig, axs = plt.subplots(1, len(variables), figsize=(4 * len(variables), 3), squeeze=False)
    for ax, v in zip(axs[0], variables):
        x = np.linspace(v.range[0], v.range[1], n_points)
        for t in v.terms:
            ax.plot(x, evaluate_mf(t.mf, t.params, x), label=t.name)
        ax.set_title(v.name)
        ax.set_ylim(-0.05, 1.05)
        ax.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def save(fig: plt.Figure, path) -> Path:
    """Write a figure atomically (format from the suffix) and close it.

    A full disk, a read-only directory or a file where the directory should be raises
    :class:`fuzzynav.errors.OutputError`; an older figure at ``path`` is then left as it was.
    """
    path = Path(path)
    try:
        return write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=110), suffix=path.suffix,
                            what="figure")
    finally:
        plt.close(fig)
