"""What a streamed run keeps for its figures: errors and event logs at the output rate.

A whole run's figures (``fuzzynav run --plot``) come from its whole solution, truth and
event logs; a streamed run of a mission holds none of them.  :class:`StreamTrace` keeps,
chunk by chunk, the errors of the kept (decimated) outputs against the chunk's truth and
each sensor's event log thinned to the first epoch of each output period, so the error
and adaptation curves of a day's run cost what its kept outputs cost.  At the full output
rate the errors are those of the whole run's solution, row by row the same arithmetic
(1e-12 relative asserted, tests/test_streamtrace.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzynav.filters.result import EventLog
from fuzzynav.filters.sensor_tables import concat_event_logs
from fuzzynav.metrics import NavErrors, errors_vs_trajectory

__all__ = ["StreamTrace", "Trace"]

_EVENT_ARRAYS = ("time_s", "residual", "S_diag", "nis", "flag", "diag")


@dataclass(frozen=True)
class Trace:
    """A streamed run's figures' data.

    Attributes
    ----------
    errors : NavErrors
        Errors of the kept outputs against the truth.
    events : dict
        Sensor name -> :class:`~fuzzynav.filters.result.EventLog`, at most one epoch per
        output period (every epoch without an output rate).
    """

    errors: NavErrors
    events: dict


class StreamTrace:
    """Gathers a :class:`Trace` chunk by chunk.

    Parameters
    ----------
    output_rate_hz : float, optional
        The run's output rate: the event logs keep the first epoch of each
        ``1 / output_rate_hz`` period; ``None`` keeps every epoch.
    """

    def __init__(self, output_rate_hz: float | None = None):
        self.rate_hz = output_rate_hz
        self._errors, self._events, self._last_bin = [], {}, {}

    def add_chunk(self, kept, truth, logs: dict) -> None:
        """The chunk's kept outputs (scored against its ``truth``) and event logs."""
        self._errors.append(errors_vs_trajectory(kept, truth))
        for name, ev in logs.items():
            self._events.setdefault(name, []).append(self._thin(name, ev))

    def _thin(self, name: str, ev: EventLog) -> EventLog:
        if self.rate_hz is None or not ev.time_s.size:
            return ev
        bins = np.floor(ev.time_s * self.rate_hz)
        # the first epoch of each output period, the period carried across chunks
        prev = np.concatenate([[self._last_bin.get(name, -math.inf)], bins[:-1]])
        sel = np.flatnonzero(bins > prev)
        self._last_bin[name] = float(bins[-1])
        return EventLog(**{f: getattr(ev, f).take(sel, 0) for f in _EVENT_ARRAYS},
                        diag_names=ev.diag_names, channels=ev.channels)

    def trace(self) -> Trace:
        """Everything gathered so far."""
        parts = self._errors
        errors = NavErrors(*(np.concatenate([getattr(p, f) for p in parts])
                             for f in ("time_s", "pos_m", "vel_mps", "att_rad")))
        return Trace(errors, {nm: concat_event_logs(evs) for nm, evs in self._events.items()})
