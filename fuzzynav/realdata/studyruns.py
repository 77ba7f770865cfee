"""Recordings as study runs: run sources (:mod:`fuzzynav.runpath`) for a study's runs.

A study's ``(scenario, seed)`` run may name a recording (``akit:akit:3``,
``rtklib:rtklib-drive@0-50%``; :mod:`.dataspec`).  :func:`recording_run` turns it into a
:class:`RecordingRun`: the filter context named filters configure themselves from
(:meth:`RecordingRun.context`), its inputs and its score against its reference.  The kind of run
follows what the loaded recording holds, so any loader of :data:`~.sources.SOURCES` fits:

* a DVL stream and a full reference (A-KIT): the filter starts from the reference and is
  aided by the DVL (:mod:`.akit`); the seed is not used (nothing is drawn);
* GNSS fixes and a reference of fixes (RTKLIB): the validation protocol's noisy fixes
  (noise drawn from the seed, defaults of :class:`~.protocol.ProtocolSettings`) fed
  throughout (:data:`STUDY_FEED`), from the start found on the data (:mod:`.session`).

A window ``@A-B`` cuts every stream at ``B`` and scores the epochs from ``A`` on.  Metrics a
recording cannot give (attitude: no attitude truth is scored) are left out.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.realdata import akit
from fuzzynav.realdata.dataspec import parse_recording_spec, resolve, until, within
from fuzzynav.realdata.protocol import ProtocolSettings
from fuzzynav.realdata.score import check_scored, errors_against, outage_scoring
from fuzzynav.realdata.session import GnssSource, context_for
from fuzzynav.realdata.sources import SOURCES, data_options
from fuzzynav.realdata.validate import fed_sigma, prepare_feeds, required_names
from fuzzynav.runpath import STREAMING_SETTINGS

__all__ = ["STUDY_FEED", "STUDY_HINT", "UNSCORED", "RecordingRun", "MIN_SCORED_S", "recording_run"]

#: which protocol feed a GNSS study run gets: the fixes throughout.  With the simulated
#: outages the free-inertial drift of a consumer MEMS IMU (hundreds of metres in 60 s,
#: docs/validation.md) would drown what a noise controller does to the aided error
STUDY_FEED = "gnss"
#: metrics a recording cannot give: left out, so that tables do not read them as diverged
UNSCORED = ("rms_pitch_deg", "rms_roll_deg", "rms_heading_deg", "rms_att_deg")


@dataclass(frozen=True)
class RecordingRun:
    """One recording (one session, one seed, one window) as a study run: a run source
    (:mod:`fuzzynav.runpath`) around the recording's own (:class:`~.akit.AkitSource`,
    :class:`~.session.GnssSource`), without the metrics a recording cannot give.

    Attributes
    ----------
    name : str
        The single-session spec (the study's "scenario" name of the run).
    seed : int
    sensors : dict
        The aiding streams a filter is given (sensor name -> SensorData).
    duration_s : float
        Length of the scored run [s].
    inner : Source
        The recording's run source.
    imu_rate_hz : float
        The rate of the IMU increments the filter is fed [Hz] (a study's ``[streaming]``
        ``chunk_s`` is a whole number of them).
    """

    name: str
    seed: int
    sensors: dict
    duration_s: float
    inner: object
    imu_rate_hz: float

    # the study's window sets start and length; the kind's protocol defaults the rest
    SETTINGS = frozenset({"mc"}) | STREAMING_SETTINGS
    KIND = "study runs on recordings"
    SETTINGS_NOTE = ("a run's start and length are its recording window "
                     "(akit:DIR:N@START-END), scored from the window's start")

    def context(self, options=None):
        """The :class:`~fuzzynav.filters.named.FilterContext` of this run."""
        return self.inner.context(options)

    def inputs(self, setup):
        return self.inner.inputs(setup)

    def score(self, result) -> dict:
        return _scored(self.inner.score(result))

    def streaming_scorer(self):
        """The recording source's streaming scorer (fed each chunk of the solution)."""
        return self.inner.streaming_scorer()

    def score_streamed(self, result, scorer) -> dict:
        """:meth:`score` of a run fed chunk by chunk to ``scorer``: the same metrics."""
        return _scored(self.inner.score_streamed(result, scorer))

    def required(self, metrics: dict) -> tuple:
        return self.inner.required(metrics)


def _scored(metrics: dict) -> dict:
    """``metrics`` without those a recording cannot give (:data:`UNSCORED`)."""
    return {k: v for k, v in metrics.items() if k not in UNSCORED}


@lru_cache(maxsize=16)
def _load(kind: str, directory: str, session, options: str | None = None):
    """A loaded recording (kept: the two halves of a split and every seed share it)."""
    start = None if options is None else data_options(f"{kind}:{directory}?{options}")
    kw = {} if start is None else {"options": start}
    try:
        loaded = SOURCES[kind].load(directory, session=session, **kw)
    except InputFileError as exc:  # too large to hold: a study cannot read it streamed
        from fuzzynav.realdata.loaders.rtklib import STREAMED_HINT

        if not exc.what.endswith(STREAMED_HINT):
            raise
        raise InputFileError(exc.path, exc.where, exc.what[:-len(STREAMED_HINT)]
                             + STUDY_HINT) from None
    return loaded[0] if isinstance(loaded, list) else loaded


#: what a study says of a recording too large to hold (its runs hold it: every trial runs
#: it again, so it is not read from its file chunk by chunk)
STUDY_HINT = ("a study holds its recordings (each trial runs them again): raise "
              "$FUZZYNAV_MAX_MEMORY_GB, or study a shorter recording")


#: shortest stretch of a recording a study may score [s]: a window past the end, or of a few
#: seconds, would score nothing (a division by a zero distance) or noise
MIN_SCORED_S = 10.0


def recording_run(name: str, seed: int = 0) -> RecordingRun:
    """The :class:`RecordingRun` of a single-session recording spec and a seed.

    Raises
    ------
    FuzzynavError
        A malformed spec, a missing directory (``DataMissingError``) or a recording the
        loader refuses (``InputFileError``).
    """
    spec = parse_recording_spec(name)
    rec = _load(spec.kind, str(resolve(spec)), spec.session, spec.options)
    t_first, t_last = float(rec.imu.time_s[0]), float(rec.imu.time_s[-1])
    lo, hi = spec.window.bounds(t_first, t_last) if spec.window else (t_first, t_last)
    if not hi - lo >= MIN_SCORED_S:
        raise FuzzynavError(f"{name}: window {spec.window} leaves {max(hi - lo, 0.0):.3g} s to "
                            f"score (at least {MIN_SCORED_S:g}: MIN_SCORED_S); the recording "
                            f"runs 0-{t_last - t_first:.0f} s")
    if hasattr(rec, "dvl"):
        return _dvl_run(name, seed, rec, lo, hi)
    if hasattr(rec, "gnss"):
        return _gnss_run(name, seed, rec, lo, hi)
    raise FuzzynavError(f"{name}: a {spec.kind} recording has neither a DVL nor GNSS "
                        "stream a study can run")


def _dvl_run(name, seed, rec, lo, hi) -> RecordingRun:
    """An A-KIT-like run: start from the reference, DVL aiding, scored in ``[lo, hi]``."""
    cut = replace(rec, imu=until(rec.imu, hi), dvl=until(rec.dvl, hi))
    ref = within(rec.reference, lo, hi)
    return RecordingRun(name, int(seed), {"dvl": cut.dvl}, hi - lo,
                        akit.AkitSource(cut, ref, name), cut.imu.rate_hz)


def _gnss_run(name, seed, rec, lo, hi,
              settings: ProtocolSettings = ProtocolSettings()) -> RecordingRun:
    """A GNSS recording under the validation protocol (:data:`STUDY_FEED`), scored in
    ``[lo, hi]``."""
    cut = replace(rec, imu=until(rec.imu, hi), gnss=until(rec.gnss, hi),
                  reference=until(rec.reference, hi))
    feeds, windows, start, lever = prepare_feeds(cut, settings, seed)
    sigma0 = fed_sigma(cut, settings)
    t0 = max(settings.t_start_s, start.init.time_s, lo)
    if not hi - t0 >= MIN_SCORED_S:
        raise FuzzynavError(f"{name}: {max(hi - t0, 0.0):.3g} s left to score after the start "
                            f"at {t0 - float(rec.imu.time_s[0]):.0f} s (at least "
                            f"{MIN_SCORED_S:g}: MIN_SCORED_S); widen the window")
    check_scored(cut.reference, t0, hi, name)

    fixes = feeds[STUDY_FEED]
    vel_scored = bool(np.isfinite(cut.reference.z[:, 3:6]).all())
    source = GnssSource(
        name, int(seed), start,
        lambda options: context_for(fixes, options, init_pos_sigma_m=sigma0),
        outage_scoring(
            lambda res: errors_against(res, cut.reference, lever, settings.velocity_lag_s),
            windows, t0),
        lambda m: required_names(m, vel_scored), settings.use_velocity)
    return RecordingRun(name, int(seed), {"gnss": fixes}, hi - t0, source, cut.imu.rate_hz)
