"""Start a filter on a recording: initial state from the data, then one named-filter run.

The filter starts at the end of the opening rest (:func:`fuzzynav.realdata.coarse_align.
initial_state`): level from the accelerometers, heading from the GNSS course once moving
(or by specific-force matching without a mounting), position and velocity from the fed
fixes.  The mean gyro rate at rest (turn-on bias; earth rate removed) is subtracted from
the angle increments beforehand, because the filter starts its sensor-error states at zero
(:func:`fuzzynav.filters.runner.run_filter` takes no prior estimate); the filter then
estimates what is left.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from fuzzynav.errors import InputFileError, OutputRateError
from fuzzynav.filters.named import FilterContext
from fuzzynav.filters.runner import InitialState
from fuzzynav.nav import attitude, earth
from fuzzynav.realdata.loaders.imu_file import ImuCut, without_gyro_bias
from fuzzynav.realdata.mems import CONSUMER_MEMS, MemsModel
from fuzzynav.realdata.reference_scoring import ReferenceScoring
from fuzzynav.runpath import RUN_SETTINGS, RunInputs
from fuzzynav.realdata import coarse_align
from fuzzynav.sim.imu import ImuData

__all__ = ["GNSS_SENSOR", "Start", "start_from", "constraints_for", "GnssSource",
           "context_for"]

#: the name of the GNSS stream; rule-file bindings may name it or its kind ``gnss``
GNSS_SENSOR = "gnss"


@dataclass(frozen=True)
class Start:
    """Where and how the filter starts.

    Attributes
    ----------
    imu : ImuData or ImuCut
        The increments from the start on, the rest gyro bias removed (an
        :class:`~fuzzynav.realdata.loaders.imu_file.ImuCut`, read from the file chunk by
        chunk, for a recording loaded ``streamed``).
    init : InitialState
        The navigation state at ``imu.time_s[0]`` (IMU position).
    coarse : coarse_align.StartEstimate
        What the initialisation found (rest period, level, heading method, gyro bias).
    """

    imu: ImuData
    init: InitialState
    coarse: object


def start_from(imu, fixes, mounting_known: bool, lever_arm_b=(0.0, 0.0, 0.0),
               options=None) -> Start:
    """Initial state from the data (``fixes``: the stream the filter will be fed; ``options``:
    :class:`~fuzzynav.realdata.start_options.StartOptions`, default the car drive's).

    Raises
    ------
    InputFileError
        When the recording has no opening rest or no motion to find the heading.
    """
    held = imu.window(imu.span_s[0], coarse_align.reads_until_s(imu.span_s, fixes, options)) \
        if hasattr(imu, "window") else imu  # a recording read from its file: its opening
    s = coarse_align.initial_state(held, fixes, forward_known=mounting_known, options=options)
    k = int(np.searchsorted(held.time_s, s.time_s - 1e-9))
    if k >= imu.n_samples - 1:
        raise InputFileError(None, "initialisation", f"the opening rest ends at "
                             f"{s.time_s:.2f} s, at the end of the IMU data")
    t0 = float(held.time_s[k])
    if hasattr(imu, "window"):
        cut = ImuCut(imu, k, s.gyro_bias_rps, t0)
    else:
        cut = without_gyro_bias(ImuData(time_s=imu.time_s[k:], dtheta_b=imu.dtheta_b[k:],
                                        dv_b=imu.dv_b[k:], meta=imu.meta), s.gyro_bias_rps)
    q_bn = attitude.euler_to_quat(s.att)
    # the fixes are the antenna's; the state is the IMU's
    l_n = attitude.quat_to_dcm(q_bn) @ np.asarray(lever_arm_b, float)
    dlat, dlon, dh = earth.enu_to_delta_lla(l_n, s.lla[0], s.lla[2])
    lla = s.lla - np.array([dlat, dlon, dh])
    return Start(cut, InitialState(t0, lla, np.asarray(s.vel_n, float), q_bn), s)


def constraints_for(start: Start, sigma_mps: float, rate_hz: float):
    """Non-holonomic constraint epochs over the run (kind ``nhc``), or ``None`` if off."""
    if not sigma_mps > 0.0:
        return None
    from fuzzynav.sim.sensors import SensorData

    t0, t1 = start.imu.span_s
    t = np.arange(t0 + 1.0 / rate_hz, t1, 1.0 / rate_hz)
    return SensorData("nhc", t, np.zeros((t.size, 2)), np.full((t.size, 2), float(sigma_mps)))


@dataclass(frozen=True)
class GnssSource:
    """A recording fed GNSS fixes (and constraints) from a :class:`Start`, as a run source
    (:mod:`fuzzynav.runpath`).

    Attributes
    ----------
    name : str
    seed : int
        The seed of the fed noise.
    start : Start
    make_context : callable
        ``make_context(options) -> FilterContext`` (:func:`context_for`); its ``sensors``
        are the fed streams.
    scorer : ReferenceScoring or callable
        ``scorer(result) -> metrics`` against the reference; a
        :class:`~fuzzynav.realdata.reference_scoring.ReferenceScoring` also scores a run
        streamed chunk by chunk (``--output-rate``, ``--chunk``).
    needed : callable
        ``needed(metrics) -> names`` of the metrics that must be finite.
    use_velocity : bool
        Whether the GNSS velocities are used.
    """

    name: str
    seed: int
    start: Start
    make_context: Callable
    scorer: Callable
    needed: Callable
    use_velocity: bool = True

    # every run setting applies: the validation protocol degrades what the receiver logged,
    # and the reference scores a streamed run chunk by chunk (reference_scoring)
    SETTINGS = frozenset(RUN_SETTINGS)
    KIND = "rtklib recordings"
    SETTINGS_NOTE = "every run setting applies"

    def context(self, options=None) -> FilterContext:
        return self.make_context(options)

    def inputs(self, setup) -> RunInputs:
        return RunInputs(self.start.imu, self.make_context(None).sensors, self.start.init,
                         {GNSS_SENSOR: {"use_velocity": bool(self.use_velocity)}})

    def score(self, result) -> dict:
        return self.scorer(result)

    def streaming_scorer(self):
        """A streaming form of :meth:`score`, fed each chunk of the solution.

        Raises
        ------
        OutputRateError
            When :attr:`scorer` is a plain function (it scores whole results only).
        """
        if not isinstance(self.scorer, ReferenceScoring):
            raise OutputRateError(f"{self.name} is scored on its whole result, so its "
                                  "output cannot be decimated")
        return self.scorer.streaming()

    def score_streamed(self, result, scorer) -> dict:
        """:meth:`score` of a run fed chunk by chunk to ``scorer``: the same metrics."""
        return self.scorer.streamed(result, scorer)

    def required(self, metrics: dict) -> tuple:
        return self.needed(metrics)


def context_for(fixes, options=None, mems: MemsModel = CONSUMER_MEMS,
                init_pos_sigma_m: float = 2.0, constraints=None) -> FilterContext:
    """What a named filter configures itself from on a recording: the MEMS model, its
    initial sigmas under ``options`` (which override them), the fed fixes (sensor
    :data:`GNSS_SENSOR`) and the non-holonomic ``constraints`` (:func:`constraints_for`,
    sensor ``nhc``) if any; ``init_pos_sigma_m`` is the fed fixes' noise [m]."""
    sensors = {GNSS_SENSOR: fixes}
    if constraints is not None:
        sensors["nhc"] = constraints
    opts = dict(mems.filter_options(init_pos_sigma_m))
    opts.update(options or {})
    return FilterContext(imu_noise=mems.imu_noise(), sensors=sensors, options=opts)
