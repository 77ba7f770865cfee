"""Memory of an alignment run: refuse one that cannot fit before anything is simulated.

An alignment run simulated whole (:func:`fuzzynav.align.alignment_run.simulate`) holds its
time grid of samples and mid-points, the truth, the increments and the open-loop solution
per IMU sample (:data:`BYTES_PER_SAMPLE`); one simulated and mechanized chunk by chunk
(:func:`fuzzynav.align.alignment_run.streamed_epochs`, ``--chunk``) holds one chunk of
them.  Both hold every filter epoch: the solution there and the filter's estimate and
covariance history (:data:`BYTES_PER_EPOCH`; the transition matrices are made a block of
epochs at a time, :data:`fuzzynav.align.fine.TRANSITION_BLOCK`), and every run a few
megabytes (:data:`BASE_BYTES`).  The limit is the navigation runs'
(:func:`fuzzynav.sim.budget.memory_limit`).
"""
from __future__ import annotations

from fuzzynav.errors import InputFileError
from fuzzynav.sim.budget import human_bytes, memory_limit

__all__ = ["BYTES_PER_SAMPLE", "BYTES_PER_EPOCH", "BASE_BYTES", "estimate", "check_size"]

#: bytes per IMU sample of an alignment run simulated whole: measured 930 (tracemalloc peak
#: of paper002-gusts at 400 s and 1 600 s, align-fuzzy), rounded up
BYTES_PER_SAMPLE = 1024
#: bytes per filter epoch: measured 0.2-1.5 kB (the growth of a streamed run's peak between
#: 400 s and 1 600 s; what it holds at the end: its epochs 230 B, the filter's estimate and
#: covariance history 1.2 kB; ``benchmarks/bench_memory_figures.py``), rounded up
BYTES_PER_EPOCH = 4096
#: bytes of an alignment run whatever its length (the filter's rule system and policy, the
#: scenario, the per-run arrays): measured ~3.5 MB (a streamed run's peak less its epochs
#: and its 6 000-sample chunk), rounded up
BASE_BYTES = 8 * 2**20
#: how to ask for an alignment run in chunks, on the command line
HOW = "compare it with --chunk S (simulated and mechanized S seconds of IMU at a time)"


def estimate(scn, chunk_samples: int | None = None) -> float:
    """Bytes an alignment run of ``scn`` needs, whole or in chunks of ``chunk_samples``."""
    n = scn.duration_s * scn.imu.rate_hz
    held = n if chunk_samples is None else min(n, chunk_samples)
    return (BASE_BYTES + held * BYTES_PER_SAMPLE
            + scn.duration_s / scn.noise.period_s * BYTES_PER_EPOCH)


def check_size(scn, chunk_samples: int | None = None) -> None:
    """Refuse an alignment run whose :func:`estimate` exceeds the memory limit; whole, the
    message gives the estimate in chunks too and how to ask for it.

    Raises
    ------
    InputFileError
        Without a file; ``where`` ``duration_s``.
    """
    need, (limit, source) = estimate(scn, chunk_samples), memory_limit()
    if need <= limit:
        return
    n = scn.duration_s * scn.imu.rate_hz
    how = "" if chunk_samples is not None else (
        f". In chunks of 15 000 samples it needs ~{human_bytes(estimate(scn, 15_000))}: {HOW}")
    raise InputFileError(None, "duration_s", f"alignment scenario {scn.name}: "
                         f"{scn.imu.rate_hz:g} Hz x {scn.duration_s:g} s = {n:.3g} samples "
                         f"and {scn.duration_s / scn.noise.period_s:.3g} filter epochs need "
                         f"~{human_bytes(need)}"
                         + (" simulated whole" if chunk_samples is None else
                            f" in chunks of {chunk_samples} samples")
                         + f"; the limit is {human_bytes(limit)} ({source}){how}")
