"""The recording runs of a study file (``[train]`` / ``[test]`` ``recordings``).

A spec is ``KIND:DIR[:SESSION][@A-B[%]]`` (:mod:`fuzzynav.realdata.dataspec`); each is
parsed, its directory found, and its sessions expanded into one run per session and seed.
Every problem is one error naming the file and key (``train.recordings[0]``, ...).
"""
from __future__ import annotations

from fuzzynav.errors import FuzzynavError
from fuzzynav.realdata.dataspec import (expand, is_recording_name, overlaps,
                                        parse_recording_spec, resolve)

__all__ = ["recording_runs", "check_recordings_held_out", "check_no_attitude",
           "check_no_t_start"]


def recording_runs(t, seeds: list) -> list:
    """``(single-session spec, seed)`` of every recording of table ``t`` x ``seeds``."""
    specs = t.data.get("recordings")
    t._used.add("recordings")
    if not isinstance(specs, list) or not specs:
        raise t.error("recordings", "must be a non-empty array of recording specs "
                                    "KIND:DIR[:SESSION][@A-B[%]]")
    singles = []
    for i, text in enumerate(specs):
        try:
            spec = parse_recording_spec(text)
            resolve(spec)
            singles += [str(s) for s in expand(spec)]
        except FuzzynavError as exc:
            raise t.error(f"recordings[{i}]", str(exc)) from None
    return [(name, int(sd)) for name in dict.fromkeys(singles) for sd in seeds]


def check_recordings_held_out(tt, train: tuple, test: tuple) -> None:
    """Refuse a test recording that is, or overlaps, a training recording (same session,
    overlapping windows; any seed: the data are the same)."""
    recorded = [parse_recording_spec(n) for n, _ in train if is_recording_name(n)]
    for name, _ in test:
        if is_recording_name(name) and any(overlaps(parse_recording_spec(name), r)
                                           for r in recorded):
            raise tt.error("recordings", f"recording {name} is also (or overlaps) a "
                                         "training recording; held-out recordings must be "
                                         "other sessions or other time windows")


def check_no_attitude(ob, runs: tuple, weights: dict) -> None:
    """Recordings score no attitude (nor heading): a study on them must not weigh it."""
    if not any(is_recording_name(n) for n, _ in runs):
        return
    for group in ("att", "hdg"):
        if weights.get(group, 0.0) > 0:
            raise ob.error(f"weights.{group}", "recordings have no attitude truth: set "
                                               f"weights = {{ pos = ..., vel = ..., {group} "
                                               "= 0.0 }")


def check_no_t_start(ob, runs: tuple, t_start: float) -> None:
    """A recording is scored in its own window: ``t_start_s`` (which it would ignore) must
    not be set in a study that has recordings."""
    if t_start > 0 and any(is_recording_name(n) for n, _ in runs):
        raise ob.error("t_start_s", f"{t_start:g} s: applies to simulated runs only; a "
                                    "recording is scored in its own window (give it as "
                                    "KIND:DIR:SESSION@A-B), so t_start_s would be ignored there")
