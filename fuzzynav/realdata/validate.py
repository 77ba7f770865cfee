"""Run the protocol: one filter, one noise seed, fed with and without outages, scored.

Both runs of a seed see the same noisy fixes and start from the same state, so the
difference between them is the outages alone.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from fuzzynav.errors import InputFileError
from fuzzynav.filters.chunk_files import below
from fuzzynav.realdata import protocol
from fuzzynav.realdata.mems import CONSUMER_MEMS, MemsModel
from fuzzynav.realdata.protocol import ProtocolSettings
from fuzzynav.realdata.score import (check_scored, errors_against, outage_drifts,
                                     outage_scoring)
from fuzzynav.realdata.session import (GnssSource, Start, constraints_for, context_for,
                                       start_from)
from fuzzynav.runpath import RunOutcome, check_outcomes, run
from fuzzynav.sim.sensor_log import check_seed

__all__ = ["FEEDS", "FeedRun", "Validation", "validate", "prepare_feeds", "fed_sigma",
           "metrics_table", "POSITION_METRICS", "VELOCITY_METRICS", "DRIFT_METRICS",
           "required_names", "check_finite"]

#: feed name -> label in tables and figures
FEEDS = {"gnss": "GNSS throughout", "outages": "with outages"}


@dataclass(frozen=True)
class FeedRun:
    """One filter run on one fed stream."""

    fixes: object
    result: object
    errors: object
    metrics: dict
    drifts: list
    #: the required metrics that are not finite (:attr:`fuzzynav.runpath.RunOutcome.diverged`)
    diverged: tuple = ()


@dataclass(frozen=True)
class Validation:
    """The protocol for one filter and one noise seed.

    Attributes
    ----------
    filter : str
    seed : int
    settings : ProtocolSettings
    start : Start
    windows : ndarray (K, 2)
        Outage windows [s] (complete or not; see :class:`~.score.OutageDrift`).
    runs : dict
        Feed name (:data:`FEEDS`) -> :class:`FeedRun`.
    """

    filter: str
    seed: int
    settings: ProtocolSettings
    start: Start
    windows: np.ndarray
    runs: dict


def _start(rec, fixes, known, lever):
    try:
        return start_from(rec.imu, fixes, known, lever, getattr(rec, "start_options", None))
    except InputFileError as exc:  # name the recording (no rest, no motion in a --span)
        raise InputFileError(getattr(rec, "directory", None), exc.where, exc.what) from None


def _for_alignment(fixes):
    """The fed fixes without the added *velocity* noise, for the coarse alignment.

    Its rest detector compares the GNSS speed with 0.2 m/s, which added velocity noise of
    0.1 m/s trips at once; the velocity noise is a test of the filter, not of the alignment.
    """
    added = fixes.meta.get("added_vel_enu_mps")
    if added is None or not np.any(added):
        return fixes
    z = fixes.z.copy()
    z[:, 3:6] -= added
    return replace(fixes, z=z)


def _with_heading_sigma(mems: MemsModel, options) -> MemsModel:
    """The IMU model with the initial heading sigma of the start options, if they set one."""
    if options is None or options.heading_sigma_deg is None:
        return mems
    east, north, _ = mems.init_att_sigma_deg
    return replace(mems, init_att_sigma_deg=(east, north, float(options.heading_sigma_deg)))


def validate(rec, filter_name: str, settings: ProtocolSettings = ProtocolSettings(),
             seed: int = 0, options=None, mems: MemsModel = CONSUMER_MEMS,
             **streaming) -> Validation:
    """Feed ``filter_name`` a degraded copy of ``rec.gnss`` and score it on ``rec.reference``.

    Parameters
    ----------
    rec : Recording
        With ``imu``, ``gnss``, ``reference`` and ``mounting``.
    filter_name : str
        A named filter.
    settings : ProtocolSettings
    seed : int
        Seed of the added noise.
    options : dict, optional
        Filter options (e.g. ``rules``).
    mems : MemsModel
    **streaming
        ``chunk_samples`` and ``output_rate_hz`` of :func:`fuzzynav.runpath.run`: each
        feed's run streamed chunk by chunk and its recorded solution kept at
        ``output_rate_hz``; the metrics, errors and drifts are those of the whole run
        (:mod:`~fuzzynav.realdata.reference_scoring`).  With ``output_dir`` (a recording
        read from its file), each feed's chunks are written to ``output_dir/FEED/``
        (``gnss``, ``outages``).
    """
    mems = _with_heading_sigma(mems, getattr(rec, "start_options", None))
    feeds, windows, start, lever = prepare_feeds(rec, settings, seed)
    sigma0 = fed_sigma(rec, settings)
    t0 = max(settings.t_start_s, start.init.time_s)
    check_scored(rec.reference, t0, rec.imu.span_s[1],
                 f"recording {getattr(rec, 'directory', '')}")
    runs = {}
    nhc = constraints_for(start, settings.nhc_sigma_mps, settings.nhc_rate_hz)
    vel_scored = bool(np.isfinite(rec.reference.z[:, 3:6]).all())
    scored = {}  # the errors and solution times the last run was scored on
    scoring = outage_scoring(
        lambda res: errors_against(res, rec.reference, lever, settings.velocity_lag_s),
        windows, t0, scored)
    for name, fixes in feeds.items():
        source = GnssSource(
            f"{getattr(rec, 'directory', 'recording')} ({FEEDS[name]})", int(seed), start,
            lambda opts, fixes=fixes: context_for(fixes, opts, mems, sigma0, nhc),
            scoring, lambda m: required_names(m, vel_scored), settings.use_velocity)
        out = run(source, filter_name, options, **below(streaming, name))
        err = scored["errors"]
        runs[name] = FeedRun(fixes, out.result, err, out.metrics,
                             outage_drifts(err, scored["solution_time_s"], windows),
                             out.diverged)
    return Validation(filter_name, int(seed), settings, start, windows, runs)


def prepare_feeds(rec, settings: ProtocolSettings, seed: int):
    """What the filter is fed for one noise seed, and where it starts.

    Returns
    -------
    feeds : dict
        :data:`FEEDS` name -> the degraded fixes (``gnss``) and those with outages.
    windows : ndarray (K, 2)
        The outage windows.
    start : Start
        The start found on the fixes with outages.
    lever : ndarray (3,)
        The antenna lever arm in the body frame [m].
    """
    seed = check_seed(seed)  # numpy would refuse a negative one with a bare ValueError
    lever = np.asarray(rec.gnss.meta.get("lever_arm_b", np.zeros(3)), float)
    noisy = protocol.degraded_fixes(rec.gnss, settings, np.random.default_rng(seed))
    known = rec.mounting is not None
    # the windows follow the start, and the start is found on what the filter is fed
    first = _start(rec, _for_alignment(noisy), known, lever)
    windows = protocol.windows_after(first.init.time_s, rec.imu.span_s[1], settings)
    feeds = {"gnss": noisy, "outages": protocol.with_outages(noisy, windows)}
    start = _start(rec, _for_alignment(feeds["outages"]), known, lever)
    return feeds, windows, start, lever


def fed_sigma(rec, settings: ProtocolSettings) -> float:
    """The fed fixes' horizontal 1-sigma: the recording's and the added noise [m]."""
    return float(np.hypot(settings.noise_pos_m, np.median(rec.gnss.sigma[:, :2])))


def metrics_table(validations) -> pd.DataFrame:
    """One row per (feed, seed): columns ``filter`` (the feed label), ``seed``, metrics.

    The ``filter`` column holds the feed label so that :func:`fuzzynav.report.
    comparison_rows` lays the feeds out as columns.
    """
    rows = [{"filter": FEEDS[name], "seed": v.seed, "filter_name": v.filter, **run.metrics}
            for v in validations for name, run in v.runs.items()]
    return pd.DataFrame(rows)


#: metrics of every run that are always defined on a recording: a NaN is a diverged filter
POSITION_METRICS = ("rms_pos_e_m", "rms_pos_n_m", "rms_pos_u_m", "rms_pos_h_m", "rms_pos_m",
                    "max_pos_h_m")
VELOCITY_METRICS = ("rms_vel_e_mps", "rms_vel_n_mps", "rms_vel_u_mps", "rms_vel_mps")
#: defined when the run has at least one complete outage
DRIFT_METRICS = ("drift_h_rms_m", "drift_h_max_m", "outage_max_h_m")


def required_names(metrics: dict, vel_scored: bool) -> tuple:
    """The metrics of one run that must be finite.

    Legitimately NaN, so not required: the attitude RMS (a recording has no attitude
    truth); the velocity RMS when the reference lacks velocities (``vel_scored``); the
    drift of an outage that is not complete (:mod:`~fuzzynav.realdata.score`), and the
    drift summaries of a run without complete outages; ``rms_pos_h_aided_m``, whose epochs
    are a subset of ``rms_pos_h_m``'s -- it is NaN only when every scored epoch is inside
    an outage.
    """
    n_done = float(metrics.get("n_outages", 0.0))
    names = list(POSITION_METRICS) + (list(VELOCITY_METRICS) if vel_scored else [])
    if n_done >= 1:
        names += DRIFT_METRICS
    names += [c for c in metrics if c.startswith("drift_h_m_")
              and n_done >= int(c.rsplit("_", 1)[1])]
    return tuple(names)


def check_finite(validations, spec) -> None:
    """Refuse (:class:`~fuzzynav.errors.RunDivergedError`) the runs of ``validations`` if a
    metric that must be finite (:func:`required_names`) is not in any: a diverged filter
    (:func:`fuzzynav.runpath.check_outcomes`, the check every source's table passes)."""
    check_outcomes([RunOutcome(v.filter, f"{spec} ({FEEDS[name]})", v.seed, r.result,
                               r.metrics, r.diverged)
                    for v in validations for name, r in v.runs.items()], "recording")
