"""Figures of A-KIT runs: each trajectory against the reference (east/north map) and the
horizontal error against time; written atomically with :func:`fuzzynav.plots.save`."""
from __future__ import annotations

from pathlib import Path


from fuzzynav import plots  # selects a headless backend when needed
from fuzzynav.metrics import errors_vs_reference
from fuzzynav.nav import earth
from fuzzynav.realdata.score import antenna_track, horizontal

__all__ = ["plt", "map_figure", "error_figure", "write_figures"]

plt = plots.plt


def _en(lla, origin):
    d = lla - origin
    return earth.delta_lla_to_enu(d[:, 0], d[:, 1], d[:, 2], origin[0], origin[2])[:, :2]


def map_figure(recs, results, label=""):
    """Filter tracks (moved to the reference point) over the reference tracks."""
    fig, axes = plt.subplots(2, (len(recs) + 1) // 2, figsize=(3.2 * ((len(recs) + 1) // 2), 6.4),
                             squeeze=False)
    for ax, rec in zip(axes.flat, recs):
        ref = rec.reference
        track = antenna_track(results[rec.trajectory], rec.reference_offset_b)
        o = ref.lla[0]
        r, f = _en(ref.lla, o), _en(track.lla, o)
        ax.plot(r[:, 0], r[:, 1], "k-", lw=1.5, label="reference")
        ax.plot(f[:, 0], f[:, 1], "C0-", lw=1, label=label or "filter")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"trajectory {rec.trajectory}", fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(recs):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.supxlabel("east (m)")
    fig.supylabel("north (m)")
    fig.tight_layout()
    return fig


def error_figure(recs, results, label=""):
    """Horizontal error against time, one line per trajectory."""
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for rec in recs:
        ref = rec.reference
        err = errors_vs_reference(antenna_track(results[rec.trajectory], rec.reference_offset_b),
                                  ref.time_s, ref.lla, ref.vel_n)
        ax.plot(err.time_s, horizontal(err), lw=1, label=f"{rec.trajectory}")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(title="trajectory", fontsize=7, ncol=4)
    ax.set_title(f"{label}: horizontal error against the reference" if label else
                 "horizontal error against the reference")
    fig.tight_layout()
    return fig


def write_figures(recs, results, out_dir, label="filter") -> list:
    """Write the map and the error curves into ``out_dir``; return the paths."""
    out_dir = Path(out_dir)
    return [plots.save(map_figure(recs, results, label), out_dir / f"akit_{label}_map.png"),
            plots.save(error_figure(recs, results, label),
                       out_dir / f"akit_{label}_horizontal_error.png")]
