"""A streamed run's chunks written one file each: the kept outputs and the event logs.

What ``fuzzynav run --output-dir DIR`` leaves: ``DIR/chunk-NNNNNN.npz``, one per chunk in
order, each written to a temporary file and renamed (:func:`fuzzynav.fileio.write_npz`),
so a reader never sees half a chunk.  Arrays: ``time_s``, ``lla``, ``vel_n``, ``q_bn``,
``sigma``, ``sensor_states``, ``state_labels`` (the kept rows) and, per stream ``NAME``,
``events.NAME.{time_s,residual,S_diag,nis,flag,diag,diag_names}`` (the chunk's epochs).
:func:`read_chunks` joins a run's files again, checked.
"""
from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError, OutputError
from fuzzynav.fileio import write_npz
from fuzzynav.filters.result import EventLog

__all__ = ["chunk_arrays", "ChunkFiles", "ChunkedRun", "below", "read_chunks",
           "refuse_earlier_chunks", "run_files"]

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


def below(streaming: dict, name: str) -> dict:
    """Streaming options with their ``output_dir`` (if any) made its sub-directory
    ``name`` (a run of a table, a feed of the protocol, a trajectory)."""
    if streaming.get("output_dir") is None:
        return dict(streaming)
    return {**streaming, "output_dir": f"{streaming['output_dir']}/{name}"}


def run_files(streaming: dict, filter_spec: str, seed: int) -> dict:
    """Streaming options with their ``output_dir`` (if any) made the run's own directory,
    ``output_dir/FILTER-seedK`` (``--output-dir`` of a table of filters and seeds)."""
    from fuzzynav.fileio import safe_stem

    return below(streaming, f"{safe_stem(filter_spec)}-seed{int(seed)}")


@dataclass(frozen=True)
class ChunkedRun:
    """One run's chunk files joined in order (:func:`read_chunks`).

    Attributes
    ----------
    time_s, lla, vel_n, q_bn, sigma, sensor_states : ndarray
        The kept rows, as in :class:`~fuzzynav.filters.result.FilterResult`.
    state_labels : tuple of str
    events : dict
        Stream name -> :class:`~fuzzynav.filters.result.EventLog` of every chunk's epochs.
    files : tuple of Path
        The chunk files read, in order.
    """

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    q_bn: np.ndarray
    sigma: np.ndarray
    sensor_states: np.ndarray
    state_labels: tuple
    events: dict
    files: tuple


#: the kept-row arrays of a chunk file
ROW_FIELDS = ("time_s", "lla", "vel_n", "q_bn", "sigma", "sensor_states")


def read_chunks(directory) -> ChunkedRun:
    """The chunk files ``chunk-000000.npz``, ``chunk-000001.npz``, ... of one run's
    directory (``--output-dir DIR/FILTER-seedK``, a recording's ``.../FEED``) joined.

    Every file is checked before anything is joined: the numbering has no gap, each file
    holds the arrays of :func:`chunk_arrays` (read without pickles: nothing in a file is
    executed), every chunk has the first one's state labels and streams, and the kept rows'
    times increase across files.

    Raises
    ------
    InputFileError
        Naming the file (or the directory) and what is wrong with it.
    """
    directory = Path(directory)
    files = sorted(directory.glob("chunk-*.npz")) if directory.is_dir() else []
    if not files:
        below = sorted({f.parent.name for f in directory.glob("*/chunk-000000.npz")})
        raise InputFileError(directory, "", "holds no chunk files (chunk-NNNNNN.npz)" + (
            f"; its directories {', '.join(below)} do (one per feed of a recording)"
            if below else ""))
    for i, path in enumerate(files):
        if path.name != f"chunk-{i:06d}.npz":
            raise InputFileError(directory / f"chunk-{i:06d}.npz", "",
                                 f"missing: the chunks are numbered from 0 without gaps, "
                                 f"found {path.name} in its place")
    parts = [_chunk(path) for path in files]
    first = parts[0]
    last_t = None
    for path, part in zip(files, parts):
        for key, want in (("state_labels", first["state_labels"]),
                          ("streams", first["streams"])):
            if part[key] != want:
                raise InputFileError(path, key, f"{part[key]} differ from {files[0].name}'s "
                                                f"{want}: not the same run")
        _same_shapes(path, part, first)
        t = part["time_s"]
        if t.size and last_t is not None and not t[0] > last_t:
            raise InputFileError(path, "time_s", f"starts at {t[0]!r} s, not after the "
                                                 f"previous chunk's last row ({last_t!r} s)")
        last_t = t[-1] if t.size else last_t
    rows = {f: np.concatenate([p[f] for p in parts]) for f in ROW_FIELDS}
    events = {nm: EventLog(**{f: np.concatenate([p["events"][nm][f] for p in parts])
                              for f in EVENT_FIELDS},
                           diag_names=first["events"][nm]["diag_names"])
              for nm in first["streams"]}
    return ChunkedRun(**rows, state_labels=first["state_labels"], events=events,
                      files=tuple(files))


def _same_shapes(path: Path, part: dict, first: dict) -> None:
    """Refuse a chunk whose arrays do not line up: a row or event count other than its
    times', or columns other than the first chunk's."""
    groups = [(part, first, ROW_FIELDS, "")] + [
        (part["events"][nm], first["events"][nm], EVENT_FIELDS, f"events.{nm}.")
        for nm in part["streams"]]
    for got, want, fields, prefix in groups:
        rows = got["time_s"].shape[:1]
        for f in fields:
            shape, ref = got[f].shape, want[f].shape
            if shape[:1] != rows or shape[1:] != ref[1:]:
                raise InputFileError(path, prefix + f, f"has shape {shape}: expected "
                                                       f"{rows + ref[1:]} (its times' rows, "
                                                       "the first chunk's columns)")


def _chunk(path: Path) -> dict:
    """One chunk file's arrays, checked for the names :func:`chunk_arrays` writes."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise InputFileError(path, "", f"is not a readable npz file "
                                       f"({exc.__class__.__name__})") from None
    missing = [f for f in (*ROW_FIELDS, "state_labels") if f not in arrays]
    if missing:
        raise InputFileError(path, missing[0], "missing: not a chunk file of a run")
    streams = sorted({k.split(".")[1] for k in arrays if k.startswith("events.")})
    events = {}
    for nm in streams:
        got = {f: arrays.get(f"events.{nm}.{f}") for f in (*EVENT_FIELDS, "diag_names")}
        absent = [f for f, v in got.items() if v is None]
        if absent:
            raise InputFileError(path, f"events.{nm}.{absent[0]}", "missing")
        got["diag_names"] = tuple(str(s) for s in got["diag_names"])
        events[nm] = got
    return {**{f: arrays[f] for f in ROW_FIELDS},
            "state_labels": tuple(str(s) for s in arrays["state_labels"]),
            "streams": streams, "events": events}
