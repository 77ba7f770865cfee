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

from fuzzynav.fileio import write_npz

__all__ = ["chunk_arrays", "ChunkFiles", "run_files"]

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


class ChunkFiles:
    """Writes ``chunk-000000.npz``, ``chunk-000001.npz``, ... into ``out_dir``."""

    def __init__(self, out_dir):
        self.out_dir, self.count = Path(out_dir), 0

    def write(self, kept, logs: dict) -> None:
        """The next chunk's file (``kept``: its kept outputs; ``logs``: its event logs)."""
        write_npz(self.out_dir / f"chunk-{self.count:06d}.npz", chunk_arrays(kept, logs),
                  "streamed run output (--output-dir)")
        self.count += 1


def run_files(streaming: dict, filter_spec: str, seed: int) -> dict:
    """Streaming options with their ``output_dir`` (if any) made the run's own directory,
    ``output_dir/FILTER-seedK`` (``--output-dir`` of a table of filters and seeds)."""
    from fuzzynav.fileio import safe_stem

    if streaming.get("output_dir") is None:
        return dict(streaming)
    return {**streaming, "output_dir": f"{streaming['output_dir']}/{safe_stem(filter_spec)}"
                                       f"-seed{int(seed)}"}
