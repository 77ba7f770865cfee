"""A run's sensors packed for the compiled loop, and the per-sensor event logs unpacked.

:func:`sensor_tables` turns the sensors, their measurement models and bound adaptation
policies into the loop's arrays (:class:`SensorTables`); :func:`event_table` merges their
epochs in time order (per run, or per chunk of a streamed run); :func:`events` splits the
loop's per-event outputs back into one :class:`~fuzzynav.filters.result.EventLog` per sensor.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.stats import chi2

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters import adaptation, loop, measurements
from fuzzynav.filters.adaptation import N_DIAG, NoAdaptation
from fuzzynav.filters.result import EventLog

__all__ = ["SensorTables", "pack_sensors", "event_table", "event_outputs", "concat_event_logs",
           "adapter_ids", "split_events"]


class SensorTables(NamedTuple):
    """What :func:`pack_sensors` packs of a run's sensors: their ``names`` (sorted: the
    loop's sensor index), measurement ``models`` and bound adapters ``bounds``, the most
    rows ``M`` a model writes, the measurement-kernel table ``meas_fns``, the merged epochs
    ``events`` (:class:`~fuzzynav.filters.loop_args.Events`, in time order) and the per-sensor
    arrays ``sensors`` (:class:`~fuzzynav.filters.loop_args.Sensors`)."""

    names: list
    models: list
    bounds: list
    M: int
    meas_fns: tuple
    events: loop.Events
    sensors: loop.Sensors


def pack_sensors(sensors, adapters, options, gate_probability) -> SensorTables:
    """Per-sensor kernel ids, parameters, adapter arrays and gates; the merged event list."""
    names = sorted(sensors)
    models = [measurements.get(sensors[nm].kind) for nm in names]
    # only the models this run uses are compiled (the others' slots hold a stand-in)
    meas_fns, meas_index = measurements.kernel_table({measurements.MODELS.index()[m.kind]
                                                      for m in models})
    M = max([mdl.max_rows for mdl in models], default=1)
    rows = [mdl.rows(sensors[nm]) for nm, mdl in zip(names, models)]
    bounds = [adapters.get(nm, NoAdaptation()).bind(mdl, r)
              for nm, mdl, r in zip(names, models, rows)]
    pars = [np.asarray(mdl.pack(sensors[nm], options.get(nm, {})), float)
            for nm, mdl in zip(names, models)]
    s_mpar = np.zeros((max(len(names), 1), max([p.size for p in pars], default=1)))
    for i, p in enumerate(pars):
        s_mpar[i, :p.size] = p
    W = max([r.shape[1] for r in rows], default=1)
    ev = event_table(sensors, names, rows, W)
    gate = np.zeros((max(len(names), 1), M + 1))
    if gate_probability is not None:
        gate[:, 1:] = chi2.ppf(gate_probability, np.arange(1, M + 1))

    def flat(arrs, dtype):
        off = np.concatenate([[0], np.cumsum([a.size for a in arrs])]).astype(np.int64)
        cat = np.concatenate(arrs).astype(dtype) if arrs else np.zeros(1, dtype)
        return (cat if cat.size else np.zeros(1, dtype)), off

    afp, afp_off = flat([b.fp for b in bounds], float)
    aip, aip_off = flat([b.ip for b in bounds], np.int64)
    ast, ast_off = flat([b.state for b in bounds], float)
    events = loop.Events(ev["ev_t"], ev["ev_s"], ev["ev_data"])
    per_sensor = loop.Sensors(
        np.array([meas_index[m.kind] for m in models] or [0], np.int64), s_mpar,
        adapter_ids(bounds), afp, afp_off, aip, aip_off, ast, ast_off, gate)
    return SensorTables(names, models, bounds, M, meas_fns, events, per_sensor)


def event_table(sensors, names, rows, W: int) -> dict:
    """The merged, time-ordered event arrays of the streams ``names`` (their ``rows``)."""
    ev_t = np.concatenate([sensors[nm].time_s for nm in names] or [np.zeros(0)]).astype(float)
    ev_s = np.concatenate([np.full(len(r), i) for i, r in enumerate(rows)] or [np.zeros(0)])
    ev_data = np.zeros((ev_t.size, W))
    o = 0
    for r in rows:
        if r.shape[1] > W:
            raise FuzzynavError(f"a chunk's measurement rows are {r.shape[1]} wide, the "
                                f"run's {W}")
        ev_data[o:o + len(r), :r.shape[1]] = r
        o += len(r)
    order = np.argsort(ev_t, kind="stable")
    return dict(ev_t=np.ascontiguousarray(ev_t[order]),
                ev_s=np.ascontiguousarray(ev_s[order].astype(np.int64)),
                ev_data=np.ascontiguousarray(ev_data[order]), order=order)


def event_outputs(E: int, M: int) -> dict:
    """The loop's per-event output arrays for ``E`` events of at most ``M`` rows."""
    return dict(r=np.full((E, M), np.nan), S=np.full((E, M), np.nan),
                nis=np.full(E, np.nan), flag=np.zeros(E, np.int64),
                diag=np.full((E, N_DIAG), np.nan))


def concat_event_logs(parts) -> EventLog:
    """One :class:`EventLog` of a stream's consecutive chunk logs (in order)."""
    if len(parts) == 1:
        return parts[0]
    arrays = {f: np.concatenate([getattr(p, f) for p in parts])
              for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag")}
    return EventLog(**arrays, diag_names=parts[0].diag_names, channels=parts[0].channels)


def adapter_ids(bounds) -> np.ndarray:
    """The loop's adapter id per sensor: :data:`~fuzzynav.filters.loop.NO_ADAPTER` where the
    plain EKF's policy is bound (its call, all ones, is skipped)."""
    none = adaptation.kernel_table()[1][NoAdaptation.name]
    ids = [loop.NO_ADAPTER if b.kernel_id == none else b.kernel_id for b in bounds]
    return np.array(ids or [0], np.int64)


def split_events(ev, tb) -> dict:
    """The per-sensor :class:`EventLog` of the run's event arrays."""
    events = {}
    for i, (nm, mdl, bd) in enumerate(zip(tb.names, tb.models, tb.bounds)):
        # an index array: take() gathers the rows several times faster than a boolean mask
        sel = np.flatnonzero(tb.events.s == i)
        events[nm] = EventLog(time_s=tb.events.t.take(sel), residual=ev["r"].take(sel, 0),
                              S_diag=ev["S"].take(sel, 0), nis=ev["nis"].take(sel),
                              flag=ev["flag"].take(sel),
                              diag=ev["diag"][:, :len(bd.diag_names)].take(sel, 0),
                              diag_names=bd.diag_names, channels=mdl.channels)
    return events
