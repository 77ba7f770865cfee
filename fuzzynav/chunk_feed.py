"""A run's IMU read chunk by chunk, given its streams' epochs chunk by chunk too.

:func:`fuzzynav.runpath.run` wraps a source's increments made chunk by chunk (a recording
read from its file, :class:`fuzzynav.realdata.loaders.imu_file.ImuCut`) in
:class:`EpochsByChunk`, so the compiled loop's event logs are made and let go one chunk at
a time, as on a simulation made chunk by chunk (:mod:`fuzzynav.streamrun`).
"""
from __future__ import annotations

from fuzzynav.sim.stream import epochs_between

__all__ = ["EpochsByChunk"]


class EpochsByChunk:
    """A feed of increments made chunk by chunk (``chunks(n)``, ``dt_nom_s``) with the
    held streams' epochs handed out with each chunk: those after the previous chunk's last
    time up to this chunk's (from the start in the first), as a simulation made chunk by
    chunk has them (:func:`fuzzynav.sim.stream.epochs_between`), so every epoch is in
    exactly one chunk and the loop's arithmetic is the held run's.  The event logs are
    dropped after each chunk (or written, ``output_dir``).

    Parameters
    ----------
    feed : object
        With ``chunks(n)``, ``dt_nom_s``, ``n_samples`` and ``span_s``.
    sensors : dict
        The streams the filter is fed, whole.
    """

    events_per_chunk = True
    keep_events = False

    def __init__(self, feed, sensors: dict):
        self.feed, self.sensors = feed, dict(sensors)
        self.dt_nom_s, self.n_samples, self.span_s = feed.dt_nom_s, feed.n_samples, \
            feed.span_s
        self.held_bytes = getattr(feed, "held_bytes", None)
        #: what the filter configures its tables from: each stream's first epoch (the
        #: kinds, constants and row layout; the epochs come with the chunks)
        self.header = {nm: epochs_between(d, None, d.time_s[0] if d.time_s.size else 0.0)
                       for nm, d in self.sensors.items()}

    def chunks(self, n: int):
        """``(increments, epochs)`` of each chunk of ``n`` increments."""
        after = None
        for piece in self.feed.chunks(n):
            last = float(piece.time_s[-1])
            yield piece, {nm: epochs_between(d, after, last) for nm, d in self.sensors.items()}
            after = last

    def on_events(self, logs: dict) -> None:
        """A chunk's event logs: not kept."""

    def chunk_fed(self, kept) -> None:
        """Nothing more to do after a chunk."""
