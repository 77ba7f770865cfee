"""A streamed run's chunks written one file each: the kept outputs and the event logs.

What ``fuzzynav run --output-dir DIR`` leaves: ``DIR/chunk-NNNNNN.npz``, one per chunk in
order, each written to a temporary file and renamed (:func:`fuzzynav.fileio.write_npz`),
so a reader never sees half a chunk.  Arrays: ``time_s``, ``lla``, ``vel_n``, ``q_bn``,
``sigma``, ``sensor_states``, ``state_labels`` (the kept rows) and, per stream ``NAME``,
``events.NAME.{time_s,residual,S_diag,nis,flag,diag,diag_names}`` (the chunk's epochs).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzynav.errors import OutputError
from fuzzynav.fileio import write_npz

__all__ = ["chunk_arrays", "ChunkFiles", "refuse_earlier_chunks", "run_files"]

#: the fields of an event log written per stream
EVENT_FIELDS = ("time_s", "residual", "S_diag", "nis", "flag", "diag")


def chunk_arrays(result, logs: dict) -> dict:
    """A chunk's kept outputs (a :class:`~fuzzynav.filters.result.FilterResult`) and event
    logs (name -> :class:`~fuzzynav.filters.result.EventLog`) as flat ``npz`` arrays."""
    out = {"time_s": result.time_s, "lla": result.lla, "vel_n": result.vel_n,
           "q_bn": result.q_bn, "sigma": result.sigma, "sensor_states": result.sensor_states,
           "state_labels": np.array(result.state_labels, dtype=str)}
    for nm, ev in logs.items():
        out.update({f"events.{nm}.{f}": getattr(ev, f) for f in EVENT_FIELDS})
        out[f"events.{nm}.diag_names"] = np.array(ev.diag_names, dtype=str)
    return out


#: what the files are, in messages
WHAT = "streamed run output (--output-dir)"


def refuse_earlier_chunks(out_dir) -> None:
    """Refuse ``out_dir`` if it (or a directory below it) already holds chunk files: a
    reader of the directory would take an earlier run's chunks for this run's (a shorter
    run leaves the longer one's last chunks behind).

    Raises
    ------
    OutputError
        Naming the directory, how many chunk files it holds and the first of them.
    """
    out_dir = Path(out_dir)
    stale = sorted(out_dir.rglob("chunk-*.npz")) if out_dir.is_dir() else []
    if stale:
        raise OutputError(out_dir, f"it holds {len(stale)} chunk file(s) of an earlier run "
                                   f"({stale[0]}); give an empty or a new directory",
                          WHAT)


class ChunkFiles:
    """Writes ``chunk-000000.npz``, ``chunk-000001.npz``, ... into ``out_dir``, which must
    not hold chunk files yet (:func:`refuse_earlier_chunks`, before the run)."""

    def __init__(self, out_dir):
        refuse_earlier_chunks(out_dir)
        self.out_dir, self.count = Path(out_dir), 0

    def write(self, kept, logs: dict) -> None:
        """The next chunk's file (``kept``: its kept outputs; ``logs``: its event logs)."""
        write_npz(self.out_dir / f"chunk-{self.count:06d}.npz", chunk_arrays(kept, logs),
                  WHAT)
        self.count += 1


def run_files(streaming: dict, filter_spec: str, seed: int) -> dict:
    """Streaming options with their ``output_dir`` (if any) made the run's own directory,
    ``output_dir/FILTER-seedK`` (``--output-dir`` of a table of filters and seeds)."""
    from fuzzynav.fileio import safe_stem

    if streaming.get("output_dir") is None:
        return dict(streaming)
    return {**streaming, "output_dir": f"{streaming['output_dir']}/{safe_stem(filter_spec)}"
                                       f"-seed{int(seed)}"}
