"""Simulate a scenario once per (scenario, seed) and cache the result as arrays.

Randomness: each component draws from its own generator, derived from the seed and the
component's name (``SeedSequence(seed, spawn_key=(crc32(name),))``), so adding, removing
or reordering a sensor leaves the IMU noise and the other sensors' noise unchanged.

Cache: one ``.npz`` per (scenario, seed), named ``<scenario>-<seed>-<key>.npz`` with
``key`` the SHA-256 of the scenario's canonical form, the seed and :data:`DATA_VERSION`
(the scenario part cut to 64 characters).  Files are written atomically (temporary file +
``os.replace``; a full disk or a read-only directory is one
:class:`fuzzynav.errors.OutputError`, with the old file intact) and read with
``allow_pickle=False``; a file that is unreadable, incomplete or made for another key is
regenerated, never trusted.  A log larger than :func:`fuzzynav.sim.budget.cache_file_limit`
(``$FUZZYNAV_CACHE_MAX_MB``, default 512 MB) is not written: it is simulated again from its
seed when needed, which gives the same data.
"""
from __future__ import annotations

import hashlib
import operator
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.fileio import safe_stem, write_npz
from fuzzynav.sim.budget import CACHE_ENV_VAR, cache_file_limit, check_whole_run, human_bytes
from fuzzynav.sim.imu import ImuData
from fuzzynav.sim.scenario import Scenario
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.trajectory import Trajectory, generate

__all__ = ["DATA_VERSION", "SensorLog", "check_seed", "component_rng", "cache_key",
           "cache_path", "cached_log", "simulate"]

#: bump when the simulation or the file layout changes (invalidates every cache file)
DATA_VERSION = 3

_TRUTH_ARRAYS = ("time_s", "lla", "vel_n", "att", "q_bn", "dtheta_b", "dv_b", "omega_nb_b")
_IMU_ARRAYS = ("time_s", "dtheta_b", "dv_b", "gyro_bias_rps", "accel_bias_mps2")


@dataclass(frozen=True)
class SensorLog:
    """Truth and every sensor's output for one (scenario, seed).

    Attributes
    ----------
    scenario : Scenario
    seed : int
    truth : Trajectory
    imu : ImuData
        Corrupted increments, with the applied bias series.
    sensors : dict
        Sensor name -> :class:`~fuzzynav.sim.sensors.SensorData`.
    """

    scenario: Scenario
    seed: int
    truth: Trajectory
    imu: ImuData
    sensors: dict


def check_seed(seed, where: str = "seed") -> int:
    """``seed`` as an ``int`` if it is a non-negative integer.

    Raises
    ------
    InputFileError
        (also a ``ValueError``) naming ``where``, for a negative, fractional or
        non-numeric seed; numpy would take a float's integer part or refuse with a bare
        ``ValueError`` deep inside.
    """
    try:
        value = operator.index(seed)  # ints and numpy integers, not 1.5 or "3"
    except TypeError:
        raise InputFileError(None, where, f"must be a non-negative integer, got {seed!r}") \
            from None
    if value < 0:
        raise InputFileError(None, where, f"must be a non-negative integer, got {value}")
    return value


def component_rng(seed: int, name: str) -> np.random.Generator:
    """The generator of one component (``"imu"``, ``"sensor:<name>"``) for ``seed``."""
    key = zlib.crc32(name.encode("utf-8"))
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(key,)))


def cache_key(scenario: Scenario, seed: int) -> str:
    """Hex SHA-256 identifying the data of ``(scenario, seed)``."""
    text = f"fuzzynav-sim v{DATA_VERSION}\n{int(seed)}\n{scenario.canonical()}"
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _generate(scenario: Scenario, seed: int) -> SensorLog:
    truth = generate(scenario.start_lla_rad, scenario.segments, scenario.imu.rate_hz,
                     scenario.initial_speed_mps, np.deg2rad(scenario.initial_heading_deg),
                     sea=scenario.sea)
    imu = scenario.imu.corrupt(truth, component_rng(seed, "imu"))
    sensors = {name: spec.simulate(truth, component_rng(seed, f"sensor:{name}"),
                                   scenario.start_utc)
               for name, spec in scenario.sensors.items()}
    return SensorLog(scenario=scenario, seed=int(seed), truth=truth, imu=imu, sensors=sensors)


# -- file layout -------------------------------------------------------------------------------
def _to_arrays(log: SensorLog, key: str) -> dict:
    out = {"key": np.array(key), "imu_rate_hz": np.array(log.truth.imu_rate_hz),
           "sensor_names": np.array(sorted(log.sensors), dtype=str)}
    out.update({f"truth.{k}": getattr(log.truth, k) for k in _TRUTH_ARRAYS})
    out.update({f"imu.{k}": getattr(log.imu, k) for k in _IMU_ARRAYS})
    out.update({f"imu.meta.{k}": np.asarray(v) for k, v in log.imu.meta.items()})
    for name, data in log.sensors.items():
        p = f"sensor.{name}"
        out.update({f"{p}.kind": np.array(data.kind), f"{p}.time_s": data.time_s,
                    f"{p}.z": data.z, f"{p}.sigma": data.sigma})
        out.update({f"{p}.meta.{k}": np.asarray(v) for k, v in data.meta.items()})
    for k, v in out.items():
        # an object array would need a pickle, which the reader refuses: fail loudly here
        # rather than regenerating silently on every run
        if v.dtype == object:
            raise TypeError(f"cannot cache {k!r}: meta values must be numbers, strings or "
                            f"numeric arrays")
    return out


def _meta(arrays, prefix: str) -> dict:
    return {k[len(prefix):]: (arrays[k][()] if arrays[k].ndim == 0 else arrays[k])
            for k in arrays if k.startswith(prefix)}


def _from_arrays(a, scenario: Scenario, seed: int) -> SensorLog:
    truth = Trajectory(**{k: a[f"truth.{k}"] for k in _TRUTH_ARRAYS},
                       imu_rate_hz=float(a["imu_rate_hz"]), segments=scenario.segments,
                       sea=scenario.sea)
    imu = ImuData(**{k: a[f"imu.{k}"] for k in _IMU_ARRAYS}, meta=_meta(a, "imu.meta."))
    sensors = {}
    for name in a["sensor_names"].tolist():
        p = f"sensor.{name}"
        sensors[name] = SensorData(kind=str(a[f"{p}.kind"]), time_s=a[f"{p}.time_s"],
                                   z=a[f"{p}.z"], sigma=a[f"{p}.sigma"],
                                   meta=_meta(a, f"{p}.meta."))
    if sorted(sensors) != sorted(scenario.sensors):
        raise ValueError("cache holds other sensors than the scenario")
    return SensorLog(scenario=scenario, seed=int(seed), truth=truth, imu=imu, sensors=sensors)


def _read_cache(path: Path, key: str, scenario: Scenario, seed: int):
    """The cached log, or ``None`` if the file is missing, unreadable or not for ``key``."""
    try:
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        if str(arrays["key"]) != key:
            return None
        return _from_arrays(arrays, scenario, seed)
    except FileNotFoundError:
        return None
    except Exception:  # noqa: BLE001 - any damage means: regenerate, never trust
        return None


def _write_cache(path: Path, arrays: dict):
    """Write atomically; a full disk or a read-only place is one :class:`OutputError`."""
    write_npz(path, arrays, "simulation cache file (see --cache / $FUZZYNAV_CACHE)")


def cache_path(cache_dir, scenario: Scenario, seed: int) -> Path:
    """Where the cache file of ``(scenario, seed)`` lives in ``cache_dir``."""
    key = cache_key(scenario, seed)
    # the name only helps a human find the file (the key identifies it): cut long names
    return Path(cache_dir) / f"{safe_stem(scenario.name)}-{int(seed)}-{key[:16]}.npz"


def cached_log(cache_dir, scenario: Scenario, seed: int, max_bytes: float):
    """The log of ``(scenario, seed)`` in ``cache_dir`` when its file is there, intact and
    no larger than ``max_bytes``; else ``None`` (nothing is simulated or written)."""
    seed = check_seed(seed)
    path = cache_path(cache_dir, scenario, seed)
    try:
        if path.stat().st_size > max_bytes:
            return None
    except OSError:
        return None
    return _read_cache(path, cache_key(scenario, seed), scenario, seed)


def simulate(scenario: Scenario, seed: int, cache_dir=None) -> SensorLog:
    """Truth, corrupted IMU and every sensor's data for ``(scenario, seed)``.

    Parameters
    ----------
    scenario : Scenario
    seed : int
        Non-negative seed; the same (scenario, seed) always gives the same data.
    cache_dir : path-like, optional
        Directory of ``.npz`` cache files; ``None`` computes without caching.

    Returns
    -------
    SensorLog
    """
    seed = check_seed(seed)
    # a run too long to hold whole is refused here, with the estimate of streaming it
    check_whole_run(scenario.duration_s, scenario.imu.rate_hz, scenario.sensors,
                    f"scenario {scenario.name!r}")
    if cache_dir is None:
        return _generate(scenario, seed)
    key = cache_key(scenario, seed)
    path = cache_path(cache_dir, scenario, seed)
    log = _read_cache(path, key, scenario, seed)
    if log is None:
        log = _generate(scenario, seed)
        arrays = _to_arrays(log, key)
        size = sum(np.asarray(a).nbytes for a in arrays.values())
        if size <= cache_file_limit():
            _write_cache(path, arrays)
        else:  # regenerated from the seed next time: the same data, no disk filled
            _tell_not_cached(scenario, seed, size)
    return log


def _tell_not_cached(scenario: Scenario, seed: int, size: float) -> None:
    import sys

    print(f"not cached: {scenario.name} seed {seed} is {human_bytes(size)}, above the "
          f"{human_bytes(cache_file_limit())} limit of one cache file (${CACHE_ENV_VAR}); it "
          "is simulated again from its seed when needed (the same data)", file=sys.stderr)

