"""Named filters on the A-KIT AUV recordings (``fuzzynav run --data akit:DIR:1-8``).

The filter starts from the reference at the first IMU sample (as A-KIT does) with the
uncertainty :data:`INIT_OPTIONS` states, integrates the navigation-grade IMU and is aided
by the DVL alone (scale factor, misalignment and lever arm estimated as states).  It is
scored against the post-processed reference: horizontal RMS, mean and largest error, the
error at the end and that end error as a percentage of the distance travelled.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from fuzzynav.filters.chunk_files import below
from fuzzynav.filters.named import FilterContext
from fuzzynav.filters.runner import InitialState
from fuzzynav.metrics import errors_vs_reference, rms_metrics
from fuzzynav.nav import attitude, earth
from fuzzynav.realdata.reference_scoring import ReferenceScoring
from fuzzynav.realdata.score import antenna_track
from fuzzynav.runpath import STREAMING_SETTINGS, RunInputs, run
from fuzzynav.sim.imu import ImuSpec

__all__ = ["INIT_OPTIONS", "PHINS", "ROWS", "context", "initial_state", "AkitSource",
           "run_trajectory", "distance_travelled", "score", "score_errors", "run_all",
           "run_outcomes", "outcomes_table"]

#: initial uncertainty of the start taken from the reference: Delph post-processing gives
#: roll/pitch to ~0.01 deg and heading to a few 0.01 deg; its position is the reference
#: itself (0.5 m allows for the unknown IMU-to-reference offset)
INIT_OPTIONS = {"init_att_sigma_deg": (0.02, 0.02, 0.1), "init_vel_sigma_mps": 0.05,
                "init_pos_sigma_m": 0.5,
                # DVL scale/misalignment states off by default: on trajectories 1-8 they
                # drift to 1-4 % scale (the data fit within 0.4 %) absorbing heading error,
                # and the horizontal RMS is worse on 6 of 8 (docs/paper004.md)
                "sensor_states": False}
#: the filter's IMU model: a Phins-class FOG IMU; the recorded rates are rounded to 1e-4
#: rad/s (a quantization noise of 3e-5 rad/s at 100 Hz, ~0.01 deg/sqrt(h)), so the ARW
#: is set from the rounding, not from the sensor's datasheet
PHINS = ImuSpec(rate_hz=100.0, gyro_bias_sigma_dph=0.05, gyro_arw_dpsh=0.01,
                accel_bias_sigma_ug=100.0, accel_vrw_ug_psqrthz=30.0)
#: rows of the table: (label, metric)
ROWS = (("horizontal position RMS (m)", "rms_pos_h_m"),
        ("mean horizontal error (m)", "mean_pos_h_m"),
        ("max horizontal error (m)", "max_pos_h_m"),
        ("horizontal error at the end (m)", "end_pos_h_m"),
        ("  as % of the distance travelled", "end_pos_h_pct"),
        ("distance travelled (m)", "distance_m"),
        ("up position (m)", "rms_pos_u_m"),
        ("velocity RMS (m/s)", "rms_vel_mps"))


def context(rec, options=None) -> FilterContext:
    """What named filters configure themselves from on an A-KIT trajectory: the Phins IMU
    model, the DVL and :data:`INIT_OPTIONS` under ``options``."""
    opts = {**INIT_OPTIONS, **dict(options or {})}
    return FilterContext(imu_noise=PHINS.noise_si(), sensors={"dvl": rec.dvl}, options=opts)


def initial_state(rec) -> InitialState:
    """The reference at the first IMU sample, moved from the reference point to the IMU."""
    ref = rec.reference
    lla0 = _moved(ref.lla[0], ref.q_bn[0], -rec.reference_offset_b)
    return InitialState(float(rec.imu.time_s[0]), lla0, ref.vel_n[0], ref.q_bn[0])


@dataclass(frozen=True)
class AkitSource:
    """An A-KIT trajectory as a run source (:mod:`fuzzynav.runpath`): started from the
    reference, DVL-aided, scored on ``reference`` (default: the whole of ``rec``'s) at the
    reference point; position and velocity metrics must be finite (attitude is not scored).
    """

    rec: object
    reference: object = None
    label: str | None = None

    @property
    def name(self) -> str:
        return self.label or f"akit trajectory {self.rec.trajectory}"

    seed = 0
    # nothing drawn, nothing degraded: the recorded sensors as they are, the whole run
    # (streamed or not: --output-rate / --chunk)
    SETTINGS = STREAMING_SETTINGS
    KIND = "akit recordings"
    SETTINGS_NOTE = ("the filter starts from the reference, is fed the recorded sensors without "
                     "simulated outages or noise, and is scored over the whole run: nothing "
                     "depends on a seed; the loader establishes the frames and lags from the "
                     "data")

    def context(self, options=None) -> FilterContext:
        return context(self.rec, options)

    def inputs(self, setup) -> RunInputs:
        return RunInputs(self.rec.imu, {"dvl": self.rec.dvl}, initial_state(self.rec))

    @property
    def scoring(self) -> ReferenceScoring:
        """How a run is scored (:mod:`~fuzzynav.realdata.reference_scoring`): at the
        reference point, against ``reference`` (default the recording's)."""
        ref = self.rec.reference if self.reference is None else self.reference
        offset = self.rec.reference_offset_b
        return ReferenceScoring(
            lambda res: errors_vs_reference(antenna_track(res, offset), ref.time_s, ref.lla,
                                            ref.vel_n),
            lambda err, _t, res: score_errors(err, ref, res.ok))

    def score(self, result) -> dict:
        return self.scoring(result)

    def streaming_scorer(self):
        """A streaming form of :meth:`score`, fed each chunk of the solution."""
        return self.scoring.streaming()

    def score_streamed(self, result, scorer) -> dict:
        """:meth:`score` of a run fed chunk by chunk to ``scorer``: the same metrics."""
        return self.scoring.streamed(result, scorer)

    @staticmethod
    def required(metrics) -> tuple:
        """Position and velocity metrics (of ``metrics``' names): attitude is not scored."""
        return tuple(m for m in metrics if m.startswith(("rms_pos", "max_pos", "rms_vel")))


def run_trajectory(rec, filter_name: str, options=None, **streaming):
    """Run one named filter (``NAME`` or ``NAME@FILE``) on one
    :class:`~fuzzynav.realdata.loaders.akit_recording.AkitRecording`; ``(FilterResult,
    metrics dict)`` (``streaming``: ``chunk_samples``, ``output_rate_hz`` of
    :func:`fuzzynav.runpath.run`)."""
    out = run(AkitSource(rec), filter_name, options, **streaming)
    return out.result, out.metrics


def _moved(lla, q_bn, offset_b):
    """A point ``offset_b`` (body RFU, m) away from ``lla`` with attitude ``q_bn``."""
    d = attitude.quat_to_dcm(q_bn) @ np.asarray(offset_b, float)
    return np.asarray(lla, float) + np.array(earth.enu_to_delta_lla(d, lla[0], lla[2]))


def distance_travelled(ref) -> float:
    """Horizontal length of the reference track [m]."""
    d = np.diff(ref.lla, axis=0)
    enu = earth.delta_lla_to_enu(d[:, 0], d[:, 1], d[:, 2], ref.lla[1:, 0], ref.lla[1:, 2])
    return float(np.sum(np.hypot(enu[:, 0], enu[:, 1])))


def score(result, ref) -> dict:
    """RMS metrics against the reference plus the end error and its share of the distance.

    ``result`` must already be moved to the reference point (:func:`antenna_track`).
    """
    return score_errors(errors_vs_reference(result, ref.time_s, ref.lla, ref.vel_n), ref,
                        result.ok)


def score_errors(err, ref, ok: bool) -> dict:
    """:func:`score` of the errors at the reference epochs (``ok``: the run completed)."""
    m = rms_metrics(err)
    end = float(np.hypot(*err.pos_m[-1, :2])) if err.time_s.size else math.nan
    dist = distance_travelled(ref)
    m.update(end_pos_h_m=end, distance_m=dist, end_pos_h_pct=100.0 * end / dist,
             completed=float(ok))
    return m


def run_outcomes(recs, filter_name: str, options=None, **streaming) -> list:
    """One :class:`~fuzzynav.runpath.RunOutcome` per trajectory of ``recs`` (``streaming``:
    as :func:`run_trajectory`; its ``output_dir``, if any, gets a directory per trajectory,
    ``trajN``)."""
    return [run(AkitSource(rec), filter_name, options,
                **below(streaming, f"traj{rec.trajectory}")) for rec in recs]


def outcomes_table(recs, outcomes) -> tuple[pd.DataFrame, dict]:
    """Metrics per trajectory (one row each, ``filter`` = ``"traj N"``) and the results."""
    rows = [{"filter": f"traj {rec.trajectory}", "seed": rec.trajectory,
             "trajectory": rec.trajectory, "reference_offset_s": rec.clock.offset_s,
             **out.metrics} for rec, out in zip(recs, outcomes)]
    return pd.DataFrame(rows), {rec.trajectory: out.result for rec, out in zip(recs, outcomes)}


def run_all(recs, filter_name: str, options=None) -> tuple[pd.DataFrame, dict]:
    """Metrics per trajectory (one row each, ``filter`` = ``"traj N"``) and the results."""
    return outcomes_table(recs, run_outcomes(recs, filter_name, options))
