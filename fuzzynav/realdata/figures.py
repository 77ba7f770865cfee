"""Figures of a validation run: horizontal error against time, and the trajectory map.

Outage windows are shaded on the time axis and drawn in red on the map; written with
:func:`fuzzynav.plots.save` (atomic).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzynav import plots  # selects a headless backend when needed
from fuzzynav.nav import earth
from fuzzynav.realdata.score import antenna_track, horizontal
from fuzzynav.realdata.validate import FEEDS
from fuzzynav.sim.sensors.gnss import in_windows

__all__ = ["plt", "horizontal_error_figure", "trajectory_figure", "write_figures"]

plt = plots.plt


def horizontal_error_figure(v, title: str = ""):
    """Horizontal error of each fed stream against time (log scale), outages shaded."""
    fig, ax = plt.subplots(figsize=(10, 4))
    for a, b in v.windows:
        ax.axvspan(a, b, color="0.85", lw=0)
    for (name, run), ls in zip(v.runs.items(), ("-", "--")):
        h = np.maximum(horizontal(run.errors), 1e-3)
        ax.semilogy(run.errors.time_s, h, ls, lw=0.9, label=FEEDS[name])
    done = [d for d in v.runs["outages"].drifts if d.complete]
    if done:
        ax.plot([d.t_read_s for d in done], [d.drift_h_m for d in done], "rv", ms=6,
                label="drift at end of outage")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or f"{v.filter}: horizontal error (outages shaded)")
    fig.tight_layout()
    return fig


def _enu(lla, origin):
    return earth.lla_to_enu(lla[:, 0], lla[:, 1], lla[:, 2], *origin)


def trajectory_figure(v, reference, lever_arm_b=(0.0, 0.0, 0.0), title: str = ""):
    """Map (east, north) of the reference and of the solution fed with outages."""
    origin = reference.z[0, :3]
    ref = _enu(reference.z[:, :3], origin)
    res = antenna_track(v.runs["outages"].result, lever_arm_b)
    sol = _enu(res.lla, origin)
    out = in_windows(res.time_s, v.windows)
    # the solution jumps back at the first fix after an outage: break the line there
    gap = in_windows(res.time_s, v.windows + np.array([0.0, 1.0]))
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(ref[:, 0], ref[:, 1], "-", color="0.6", lw=2.5, label="RTK fixes (reference)")
    ax.plot(np.where(gap, np.nan, sol[:, 0]), np.where(gap, np.nan, sol[:, 1]), "-", lw=0.9,
            color="C0", label=f"{v.filter}, GNSS available")
    ax.plot(np.where(out, sol[:, 0], np.nan), np.where(out, sol[:, 1], np.nan), "-", lw=1.2,
            color="C3", label=f"{v.filter}, inside outages")
    for a, b in v.windows:
        k = np.searchsorted(reference.time_s, [a, b])
        k = np.clip(k, 0, reference.time_s.size - 1)
        ax.plot(ref[k, 0], ref[k, 1], "k|", ms=12, mew=2)
    ax.plot([], [], "k|", ms=12, mew=2, label="outage start / end on the reference")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or f"{v.filter}: trajectory with {len(v.windows)} simulated outages")
    fig.tight_layout()
    return fig


def write_figures(v, rec, out_dir) -> list:
    """Write both figures of validation ``v`` into ``out_dir``; return the paths."""
    out_dir = Path(out_dir)
    stem = f"{Path(rec.directory).name}_{v.filter}"
    lever = rec.gnss.meta.get("lever_arm_b", np.zeros(3))
    return [plots.save(horizontal_error_figure(v), out_dir / f"{stem}_horizontal_error.png"),
            plots.save(trajectory_figure(v, rec.reference, lever),
                       out_dir / f"{stem}_trajectory.png")]
