"""Memory budget of a simulated run: refuse a scenario that cannot fit before allocating it.

A run holds, per IMU sample, the truth and the corrupted increments, the IMU and sensor
simulation's temporaries and the filter's output and events (:data:`BYTES_PER_IMU_SAMPLE`);
the trajectory generator's quadrature temporaries are held for one block of
:data:`fuzzynav.sim.trajectory.BLOCK_SAMPLES` samples at most
(:data:`BYTES_PER_BLOCK_SAMPLE` each); and per aiding-sensor epoch a few rows of
measurements, sigmas and truth (:data:`BYTES_PER_EPOCH_COLUMN` per measurement column).
A run simulated and filtered chunk by chunk (:mod:`fuzzynav.sim.stream`,
:func:`fuzzynav.streamrun.run_streamed`) holds one chunk of samples, the epoch indices of
the streamed sensors, the sensors simulated whole and the kept outputs
(:func:`streamed_estimate`).  A scenario is refused when it is read only if it does not
fit even so (:func:`check_run_size`); one that fits only in chunks is refused when it is
simulated whole (:func:`check_whole_run`), with both estimates and the options that stream
it.  The estimate is made from the sample counts alone (duration x rate), so a scenario of
10^11 samples is refused in microseconds with the estimate in the message, not after a
``MemoryError``, a swap storm or the out-of-memory killer.

The limit is ``$FUZZYNAV_MAX_MEMORY_GB`` if set, else half of the physical memory (other
processes, and several study workers, share the machine).  Periodic outages and random
cloud spells are bounded by count (:data:`MAX_SPELLS`): each is a Python-level window.
"""
from __future__ import annotations

import os

from fuzzynav.block_sums import BLOCK_COLUMNS
from fuzzynav.errors import InputFileError

__all__ = ["BYTES_PER_IMU_SAMPLE", "BYTES_PER_BLOCK_SAMPLE", "BYTES_PER_EPOCH_COLUMN",
           "MAX_SPELLS", "DEFAULT_SHARE", "ENV_VAR", "memory_limit", "human_bytes",
           "DEFAULT_CACHE_FILE_MB", "CACHE_ENV_VAR", "cache_file_limit",
           "check_run_size", "BYTES_PER_CHUNK_SAMPLE", "BYTES_PER_STREAM_EPOCH",
           "BYTES_PER_OUTPUT_ROW", "DEFAULT_CHUNK_SAMPLES", "whole_estimate",
           "streamed_estimate", "check_whole_run", "BYTES_PER_TRUTH_SAMPLE",
           "TRUTH_STORE_BYTES", "stored_truth_bytes", "keeps_truth",
           "BYTES_PER_LOGGED_IMU_SAMPLE", "held_log_bytes", "BYTES_PER_EVENT_ROW",
           "check_run_outputs"]

#: bytes held per IMU sample of the whole run through simulation and filtering, beyond the
#: generator's block (marginal tracemalloc peaks of runs longer than a block: paper003
#: 536 B simulating + 429 B filtering its 1.4 sensor epochs per sample, paper000 424 + 92;
#: their sum, rounded up: tests/sim/test_budget.py checks it bounds a real run)
BYTES_PER_IMU_SAMPLE = 1024
#: bytes per sample of the trajectory generator's block (its quadrature nodes, profiles and
#: Picard sweeps: a 2.95 kB traced peak against 184 B kept on paper003; rounded up)
BYTES_PER_BLOCK_SAMPLE = 3072
#: bytes held per aiding-sensor epoch and measurement column (z, sigma, truth, temporaries)
BYTES_PER_EPOCH_COLUMN = 128
#: bytes per IMU sample of one chunk of a streamed run: its truth, IMU, sensor epochs,
#: trajectory temporaries and filter outputs (the whole run's per-sample and block figures
#: together: the chunk holds what a whole run holds per sample, and the block's temporaries)
BYTES_PER_CHUNK_SAMPLE = 4096
#: bytes per epoch of a sensor streamed epoch by epoch: its epoch index (int64) and the
#: temporaries of making it (the epoch times, rounding, the mask and np.unique's sort)
BYTES_PER_STREAM_EPOCH = 48
#: bytes per kept output row of a streamed run (time, navigation state, sensor states and
#: sigmas of up to 21 states: 35 floats, rounded up for the locals' and the concatenation)
BYTES_PER_OUTPUT_ROW = 1024
#: bytes a streamed run's scorer holds at most: the epochs of a block of its sums not yet
#: complete (:class:`fuzzynav.block_sums.BlockSums`), 15 rows of the run's and 4 of each
#: of two open motion segments, float64
SCORER_BYTES = BLOCK_COLUMNS * 8 * (15 + 2 * 4)
#: bytes of one sample of a kept :class:`~fuzzynav.sim.trajectory.Trajectory`: time,
#: lla, vel_n, att, omega_nb_b (3 each), q_bn (4), dtheta_b and dv_b (3 each), float64
BYTES_PER_TRUTH_SAMPLE = 8 * (1 + 3 * 4 + 4 + 3 * 2)
#: the most truth a streamed run keeps from its first pass instead of generating the
#: trajectory again chunk by chunk (:class:`fuzzynav.sim.stream.SimulatedChunks`): 128 MB,
#: 4 h at 50 Hz
TRUTH_STORE_BYTES = 128 * 2**20
#: bytes of one sample of a simulated :class:`~fuzzynav.sim.imu.ImuData`: time, dtheta_b,
#: dv_b and the applied gyro and accelerometer biases (3 each), float64
BYTES_PER_LOGGED_IMU_SAMPLE = 8 * (1 + 3 * 4)
#: IMU samples per chunk of a streamed run when none is given (5 min at 50 Hz)
DEFAULT_CHUNK_SAMPLES = 15_000
#: most outage or cloud windows a sensor may have in one run
MAX_SPELLS = 10_000
#: default share of the physical memory one run may use
DEFAULT_SHARE = 0.5
ENV_VAR = "FUZZYNAV_MAX_MEMORY_GB"
#: the largest simulation cache file written [MB]: a longer log is regenerated from its seed
DEFAULT_CACHE_FILE_MB = 512.0
CACHE_ENV_VAR = "FUZZYNAV_CACHE_MAX_MB"


def _physical_bytes() -> float:
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # not POSIX: assume a small machine
        return 8.0 * 2**30


def _positive_env(name: str, unit: str):
    """The positive finite number in ``$name``, or ``None`` when unset or empty."""
    value = os.environ.get(name)
    if not value:
        return None
    try:
        x = float(value)
    except ValueError:
        x = float("nan")
    if not x > 0.0 or x == float("inf"):
        raise InputFileError(None, name, f"must be a positive number of {unit}, got {value!r}")
    return x


def memory_limit() -> tuple[float, str]:
    """The memory one simulated run may use [bytes] and where that figure comes from."""
    gb = _positive_env(ENV_VAR, "GB")
    if gb is not None:
        return gb * 2**30, f"${ENV_VAR}"
    return DEFAULT_SHARE * _physical_bytes(), f"half the physical memory; set ${ENV_VAR} " \
                                              "to change it"


def cache_file_limit() -> float:
    """The largest simulation cache file written [bytes] (``$FUZZYNAV_CACHE_MAX_MB``, else
    :data:`DEFAULT_CACHE_FILE_MB`): a longer log is not cached but regenerated from its seed
    each time (the same data: the generators are seeded per component), so a study whose
    training set holds long runs does not fill the disk."""
    mb = _positive_env(CACHE_ENV_VAR, "MB")
    return (DEFAULT_CACHE_FILE_MB if mb is None else mb) * 2**20


def human_bytes(n: float) -> str:
    """``n`` bytes as a short figure with a binary unit (``"9.3 TB"``)."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if n < 1024.0 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1024.0
    return f"{n:.3g} PB"  # pragma: no cover


def whole_estimate(duration_s: float, imu_rate_hz: float, sensors: dict) -> float:
    """Bytes a run simulated and filtered whole holds (truth, IMU, streams, outputs)."""
    from fuzzynav.sim.trajectory import BLOCK_SAMPLES

    n_imu = duration_s * imu_rate_hz
    need = n_imu * BYTES_PER_IMU_SAMPLE + min(n_imu, BLOCK_SAMPLES) * BYTES_PER_BLOCK_SAMPLE
    return need + sum(duration_s * sp.rate_hz * _columns(sp) * BYTES_PER_EPOCH_COLUMN
                      for sp in sensors.values())


def streamed_estimate(duration_s: float, imu_rate_hz: float, sensors: dict,
                      chunk_samples: float = DEFAULT_CHUNK_SAMPLES,
                      output_rate_hz: float = 1.0) -> float:
    """Bytes a run simulated and filtered chunk by chunk holds
    (:func:`fuzzynav.streamrun.run_streamed`): one chunk of samples
    (:data:`BYTES_PER_CHUNK_SAMPLE`), the epoch indices of the streamed sensors
    (:data:`BYTES_PER_STREAM_EPOCH`), the sensors simulated whole (their epochs, as a
    whole run holds them), the scorer's block not yet summed (:data:`SCORER_BYTES`),
    the truth kept from the first pass when it fits
    :data:`TRUTH_STORE_BYTES` and the kept outputs (:data:`BYTES_PER_OUTPUT_ROW` per row
    at ``output_rate_hz``).  A run whose whole log fits :data:`TRUTH_STORE_BYTES` may
    instead be cut from its cached log, which it then holds
    (:func:`fuzzynav.sim.log_chunks.chunks_of`): the larger of the two is counted."""
    n_imu = duration_s * imu_rate_hz
    simulated = stored_truth_bytes(n_imu) if keeps_truth(n_imu, chunk_samples, sensors) \
        else 0.0
    for sp in sensors.values():
        epochs = duration_s * sp.rate_hz
        simulated += epochs * (BYTES_PER_STREAM_EPOCH if hasattr(sp, "stream")
                               else _columns(sp) * BYTES_PER_EPOCH_COLUMN)
    cached = held_log_bytes(duration_s, imu_rate_hz, sensors)
    held = max(simulated, cached if cached <= TRUTH_STORE_BYTES else 0.0)
    return (min(n_imu, chunk_samples) * BYTES_PER_CHUNK_SAMPLE + held + SCORER_BYTES
            + duration_s * output_rate_hz * BYTES_PER_OUTPUT_ROW)


def stored_truth_bytes(n_samples: float) -> float:
    """Bytes of the truth of ``n_samples`` increments (``n_samples + 1`` samples)."""
    return (n_samples + 1) * BYTES_PER_TRUTH_SAMPLE


def keeps_truth(n_samples: float, chunk_samples: float, sensors: dict,
                limit: float | None = None) -> bool:
    """Whether a streamed run keeps its first trajectory pass for its chunks
    (:class:`fuzzynav.sim.stream.SimulatedChunks`): there is such a pass (a sensor without
    a ``stream`` method is simulated whole from it), its blocks are the chunks (a chunk
    fits one trajectory block) and its truth fits ``limit`` (default
    :data:`TRUTH_STORE_BYTES`)."""
    from fuzzynav.sim.trajectory import BLOCK_SAMPLES

    limit = TRUTH_STORE_BYTES if limit is None else limit
    return (any(not hasattr(sp, "stream") for sp in sensors.values())
            and chunk_samples <= BLOCK_SAMPLES and stored_truth_bytes(n_samples) <= limit)


def held_log_bytes(duration_s: float, imu_rate_hz: float, sensors: dict) -> float:
    """Bytes a simulated :class:`~fuzzynav.sim.sensor_log.SensorLog` holds once made: its
    truth and IMU per sample and its sensors' epochs (:data:`BYTES_PER_EPOCH_COLUMN` per
    measurement column, an upper bound); what a study holds of each run it keeps in memory
    (:mod:`fuzzynav.tuning.study_streaming`)."""
    n_imu = duration_s * imu_rate_hz
    need = (n_imu + 1) * (BYTES_PER_TRUTH_SAMPLE + BYTES_PER_LOGGED_IMU_SAMPLE)
    return need + sum(duration_s * sp.rate_hz * _columns(sp) * BYTES_PER_EPOCH_COLUMN
                      for sp in sensors.values())


def _columns(spec) -> int:
    return spec.columns() if hasattr(spec, "columns") else 6


def check_run_size(duration_s: float, imu_rate_hz: float, sensors: dict) -> None:
    """Refuse a run that does not fit :func:`memory_limit` even simulated and filtered in
    chunks (:func:`streamed_estimate` with 1-Hz kept output); a run that fits only so is
    refused later, when it is simulated whole (:func:`check_whole_run`).

    Parameters
    ----------
    duration_s : float
        Length of the run [s].
    imu_rate_hz : float
    sensors : Mapping[str, Spec]
        Aiding sensors; each with ``rate_hz`` and optionally ``columns()`` (measurement
        columns per epoch, default 6), ``stream`` (simulated epoch by epoch) and
        ``spell_count(duration_s)`` returning ``(key, count)`` of its largest window
        pattern.

    Raises
    ------
    InputFileError
        Without a file; ``where`` is the key that sets the size.
    """
    n_imu = duration_s * imu_rate_hz
    need = streamed_estimate(duration_s, imu_rate_hz, sensors)
    limit, source = memory_limit()
    if need > limit:
        raise InputFileError(None, "imu.rate_hz", f"[imu] rate_hz x duration = {imu_rate_hz:g} "
                             f"Hz x {duration_s:g} s = {n_imu:.3g} samples needs "
                             f"~{human_bytes(need)} even simulated and filtered in chunks of "
                             f"{DEFAULT_CHUNK_SAMPLES} samples with 1-Hz output; the limit is "
                             f"{human_bytes(limit)} ({source})")
    for name, spec in sensors.items():
        where = f"sensors.{name}"
        if hasattr(spec, "spell_count"):
            key, count = spec.spell_count(duration_s)
            if count > MAX_SPELLS:
                raise InputFileError(None, f"{where}.{key}", f"makes ~{count:.3g} windows over "
                                     f"the {duration_s:g}-s run; at most {MAX_SPELLS} are "
                                     "supported (use longer periods or spells)")


#: how to ask for a streamed run, on the command line
STREAM_HOW = "run it with --output-rate HZ (or --chunk S, --output-dir DIR)"


def check_whole_run(duration_s: float, imu_rate_hz: float, sensors: dict,
                    what: str = "the scenario", how: str = STREAM_HOW) -> None:
    """Refuse to simulate a run whole when :func:`whole_estimate` exceeds
    :func:`memory_limit`; the message gives the streamed estimate and ``how`` to ask for it.

    Raises
    ------
    InputFileError
        ``where`` ``imu.rate_hz``.
    """
    need = whole_estimate(duration_s, imu_rate_hz, sensors)
    limit, source = memory_limit()
    if need > limit:
        streamed = streamed_estimate(duration_s, imu_rate_hz, sensors)
        raise InputFileError(None, "imu.rate_hz", f"{what}: [imu] rate_hz x duration = "
                             f"{imu_rate_hz:g} Hz x {duration_s:g} s = "
                             f"{duration_s * imu_rate_hz:.3g} samples needs "
                             f"~{human_bytes(need)} simulated whole; the limit is "
                             f"{human_bytes(limit)} ({source}). Simulated and filtered in "
                             f"chunks it needs ~{human_bytes(streamed)}: {how}")


def check_held_logs(held: dict, working_bytes: float, what: str, how: str) -> None:
    """Refuse a set of runs whose logs, held at once, and the run filtered meanwhile need
    more than :func:`memory_limit` (a study keeps every run's log it simulated).

    Parameters
    ----------
    held : Mapping[str, float]
        Bytes held per run (label -> :func:`held_log_bytes`).
    working_bytes : float
        What the largest run needs while it is filtered (:func:`whole_estimate` or
        :func:`streamed_estimate`).
    what, how : str
        What holds the runs; how to hold fewer.

    Raises
    ------
    InputFileError
        Without a file or a key: the caller names them.
    """
    total = sum(held.values())
    limit, source = memory_limit()
    if held and total + working_bytes > limit:
        big = max(held, key=held.get)
        raise InputFileError(None, "", f"{what}: the logs of its {len(held)} simulated runs, "
                             f"held at once, need ~{human_bytes(total)} (the largest, {big}, "
                             f"~{human_bytes(held[big])}) and a run filtered meanwhile "
                             f"~{human_bytes(working_bytes)}; the limit is "
                             f"{human_bytes(limit)} ({source}): {how}")


#: bytes per epoch of a sensor's event log (time, residuals, innovation variances, NIS,
#: flag and adaptation diagnostics of up to six channels: ~20 floats), rounded up for the
#: loop's event arrays and their copy into the log
BYTES_PER_EVENT_ROW = 512
#: how to keep fewer of a run's outputs
DECIMATE_HOW = ("keep fewer outputs: --output-rate HZ on the command line, [streaming] "
                "output_rate_hz in a study")


def output_bytes(output_rows: float, epochs: float = 0.0) -> float:
    """Bytes of a run's recorded outputs (:data:`BYTES_PER_OUTPUT_ROW` a row) and event
    logs (:data:`BYTES_PER_EVENT_ROW` an epoch)."""
    return output_rows * BYTES_PER_OUTPUT_ROW + epochs * BYTES_PER_EVENT_ROW


def check_run_outputs(what: str, held_bytes: float, output_rows: float, epochs: float,
                      how: str = DECIMATE_HOW, made_rows: float = 0.0) -> None:
    """Refuse a filter run whose recorded outputs, event logs and the data it is given
    need more than :func:`memory_limit`, before the run allocates them (every run passes
    here: :func:`fuzzynav.runpath.run`).  A recording is held as loaded, and an
    undecimated day of a 10-Hz solution holds ~0.9 GB.

    Parameters
    ----------
    what : str
        The run (its source's name).
    held_bytes : float
        The data the run is given, already held (IMU and sensor arrays).
    output_rows : float
        Rows of the recorded solution kept (:data:`BYTES_PER_OUTPUT_ROW` each).
    epochs : float
        Sensor epochs the event logs record (:data:`BYTES_PER_EVENT_ROW` each).
    how : str
    made_rows : float
        Rows made at once before they are decimated to the kept ones (a chunk's, or the
        whole run's in one piece), held beside them.

    Raises
    ------
    InputFileError
        Without a file; ``where`` names the run.
    """
    out = output_bytes(output_rows + made_rows, epochs)
    limit, source = memory_limit()
    if held_bytes + out > limit:
        made = f" (and {made_rows:.3g} made at a time before decimation)" if made_rows else ""
        raise InputFileError(None, what, f"its {output_rows:.3g} kept outputs{made} and "
                             f"{epochs:.3g} sensor epochs need ~{human_bytes(out)} beside the "
                             f"~{human_bytes(held_bytes)} of data it is given; the limit is "
                             f"{human_bytes(limit)} ({source}): {how}")
