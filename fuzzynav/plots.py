"""Figures: navigation error curves and adaptation factors over time (matplotlib).

Functions return the matplotlib Figure; :func:`save` writes it atomically.  The Agg backend
is selected when no display is available, so the CLI works on servers.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import matplotlib

if not os.environ.get("DISPLAY") and matplotlib.get_backend().lower() not in ("agg", "pdf", "svg"):
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

_AXES = ("east", "north", "up")
_STYLES = ("-", "--", "-.", ":")


def error_curves(errors: dict, title: str = "") -> plt.Figure:
    """Position, velocity and attitude errors of one or more filters against time.

    Parameters
    ----------
    errors : dict
        Label -> :class:`fuzzynav.metrics.NavErrors`.
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
    axs[0, 0].legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def adaptation_curves(series: dict, title: str = "") -> plt.Figure:
    """Adaptation diagnostics (alpha, DoM, R scale, ...) against time.

    Parameters
    ----------
    series : dict
        Label -> ``(time_s, values)``.
    """
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for j, (label, (t, v)) in enumerate(series.items()):
        ax.plot(t, v, _STYLES[j % len(_STYLES)], lw=0.9, label=label)
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def save(fig: plt.Figure, path) -> Path:
    """Write a figure atomically (format from the suffix) and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        plt.close(fig)
    return path
