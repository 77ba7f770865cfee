"""Checks across the fields of a scenario: values that parse but would mean nothing.

Each field of a scenario file is range-checked where it is read; what is checked here
needs several of them at once — the run's length against the IMU rate (memory, segment
lengths), the sensors' rates and windows against the run, the start latitude against the
distance the vehicle can travel.  Every refusal is an :class:`InputFileError` without a
file whose ``where`` is the key to change.
"""
from __future__ import annotations

import contextlib
import contextvars
import math

from fuzzynav.errors import InputFileError
from fuzzynav.sim.budget import check_run_size

__all__ = ["MAX_SPEED_MPS", "POLE_MARGIN_DEG", "check_scenario", "as_base"]

#: fastest vehicle the near-surface Earth model is meant for [m/s] (jets fly < 1000 m/s)
MAX_SPEED_MPS = 3000.0
#: closest approach to a pole [deg of latitude]: the ENU mechanization's longitude rate
#: ``v_e / (R cos lat)`` and the transport rate's ``tan lat`` blow up at the poles
POLE_MARGIN_DEG = 0.5
#: metres per degree of latitude (meridian arc, to 1 %)
_M_PER_DEG = 111_000.0
#: shortest s-turn, in IMU samples (a turn needs samples to be seen at all)
_MIN_TURN_SAMPLES = 2


#: set while a scenario is built only as another's ``base =`` (:func:`as_base`)
_AS_BASE = contextvars.ContextVar("fuzzynav_scenario_as_base", default=False)


@contextlib.contextmanager
def as_base():
    """Build scenarios inside this block only as the ``base =`` of another: every check
    runs but the run's size (:func:`~fuzzynav.sim.budget.check_run_size`).  A base is never
    simulated; the scenario derived from it is checked whole, its own length included, so
    a short flight derived from a long base is not refused for the base's length."""
    token = _AS_BASE.set(True)
    try:
        yield
    finally:
        _AS_BASE.reset(token)


def check_scenario(segments, imu, sensors, start: dict) -> None:
    """Refuse a scenario that would exhaust memory or whose values mean nothing.

    Parameters
    ----------
    segments : sequence of Segment
    imu : ImuSpec
    sensors : Mapping[str, Spec]
    start : dict
        ``start_lat_deg``, ``initial_speed_mps`` (the parsed ``[start]`` table) and
        optionally the other start values of :class:`~fuzzynav.sim.scenario.Scenario`.
    """
    _check_start(start)
    duration = float(sum(s.duration_s for s in segments))
    if not _AS_BASE.get():
        check_run_size(duration, imu.rate_hz, sensors)
    _check_segments(segments, imu.rate_hz)
    _check_speed_and_pole(segments, start)
    for name, spec in sensors.items():
        _check_sensor(f"sensors.{name}", spec, imu.rate_hz, duration)


#: Scenario attribute -> key of the [start] table
_START_KEYS = {"start_lat_deg": "lat_deg", "start_lon_deg": "lon_deg", "start_h_m": "h_m",
               "initial_speed_mps": "speed_mps", "initial_heading_deg": "heading_deg"}


def _check_start(start: dict) -> None:
    """Finite start values and a latitude on the globe (a file's ranges are checked as it
    is read; a Scenario built in Python comes here unchecked)."""
    for attr, key in _START_KEYS.items():
        value = start.get(attr, 0.0)
        try:
            ok = math.isfinite(value)
        except TypeError:
            ok = False
        if not ok:
            raise InputFileError(None, f"start.{key}", f"must be a finite number, got {value!r}")
    if not -90.0 <= start["start_lat_deg"] <= 90.0:
        raise InputFileError(None, "start.lat_deg", f"{start['start_lat_deg']:g} deg is not a "
                                                    "latitude (-90 to 90)")


def _check_segments(segments, rate_hz: float) -> None:
    dt = 1.0 / rate_hz
    for i, seg in enumerate(segments):
        if seg.duration_s < dt:
            raise InputFileError(None, f"segments[{i}].duration_s",
                                 f"{seg.duration_s:g} s is shorter than one IMU sample "
                                 f"(1 / {rate_hz:g} Hz = {dt:g} s)")
        if seg.kind == "s-turns" and seg.duration_s / seg.n_turns < _MIN_TURN_SAMPLES * dt:
            raise InputFileError(None, f"segments[{i}].n_turns",
                                 f"{seg.n_turns} turns in {seg.duration_s:g} s last less than "
                                 f"{_MIN_TURN_SAMPLES} IMU samples each")


def _check_speed_and_pole(segments, start: dict) -> None:
    speed = start["initial_speed_mps"]
    if speed > MAX_SPEED_MPS:
        raise InputFileError(None, "start.speed_mps", f"{speed:g} m/s is faster than "
                                                      f"{MAX_SPEED_MPS:g} m/s")
    path_m = 0.0
    for i, seg in enumerate(segments):
        end = speed + seg.speed_change_mps if seg.kind == "accelerate" else speed
        if end > MAX_SPEED_MPS:
            raise InputFileError(None, f"segments[{i}].speed_change_mps",
                                 f"the speed would reach {end:g} m/s; at most "
                                 f"{MAX_SPEED_MPS:g} m/s")
        path_m += max(speed, end) * seg.duration_s
        speed = max(end, 0.0)
    lat = start["start_lat_deg"]
    room_m = (90.0 - abs(lat)) * _M_PER_DEG - path_m
    if room_m < POLE_MARGIN_DEG * _M_PER_DEG:
        raise InputFileError(None, "start.lat_deg",
                             f"a run starting at {lat:g} deg and travelling up to "
                             f"{path_m / 1000:.3g} km may come within {POLE_MARGIN_DEG} deg "
                             "of a pole, where the ENU mechanization is singular")


def _check_window(where: str, start_s: float, end_s: float, duration: float) -> None:
    if start_s >= duration:
        raise InputFileError(None, where, f"starts at {start_s:g} s, after the end of the "
                                          f"run ({duration:g} s)")
    if start_s <= 0.0 and end_s >= duration:
        raise InputFileError(None, where, f"[{start_s:g}, {end_s:g}] s covers the whole "
                                          f"{duration:g}-s run: the sensor would give no data")


def _check_sensor(where: str, spec, imu_rate_hz: float, duration: float) -> None:
    if spec.rate_hz > imu_rate_hz:
        raise InputFileError(None, f"{where}.rate_hz",
                             f"{spec.rate_hz:g} Hz is above the IMU rate ({imu_rate_hz:g} Hz): "
                             "epochs fall on IMU samples, so fixes would be merged")
    start = getattr(spec, "start_s", 0.0)
    if start >= duration:
        raise InputFileError(None, f"{where}.start_s", f"the first epoch ({start:g} s) is "
                                                       f"after the end of the run "
                                                       f"({duration:g} s)")
    for key in ("outages", "cloud_windows"):
        for i, (a, b) in enumerate(getattr(spec, key, ())):
            _check_window(f"{where}.{key}[{i}]", a, b, duration)
    for i, w in enumerate(getattr(spec, "noise_windows", ())):
        if w.start_s >= duration:
            _check_window(f"{where}.noise_windows[{i}].start_s", w.start_s, w.end_s, duration)
    first = getattr(spec, "outage_first_s", None)
    if first is not None and first >= duration:
        raise InputFileError(None, f"{where}.outage_first_s",
                             f"{first:g} s is after the end of the run ({duration:g} s)")
