"""Named state blocks of the alignment filters (no literal indices elsewhere).

Paper 002's state ``[dvE dvN, phiE phiN phiU, nablaE nablaN, epsE epsN epsU]`` is
``vel`` (2), ``att`` (3), ``accel_bias`` (2), ``gyro_bias`` (3); the velocity-matching form
(PSINS ``alignvn``) keeps the vertical channel: ``vel`` (3) and ``accel_bias`` (3).
Axis numbers inside a block are ENU (``vel``, ``att``) or body RFU (the biases).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["AlignLayout", "LAYOUT_10", "LAYOUT_12"]

#: axis numbers inside a three-axis block
EAST, NORTH, UP = 0, 1, 2


@dataclass(frozen=True)
class AlignLayout:
    """Blocks ``(name, size)`` in state order; slices by name."""

    blocks: tuple

    @property
    def n(self) -> int:
        """Number of states."""
        return sum(size for _, size in self.blocks)

    def __getitem__(self, name: str) -> slice:
        start = 0
        for block, size in self.blocks:
            if block == name:
                return slice(start, start + size)
            start += size
        raise KeyError(name)

    def size(self, name: str) -> int:
        """Length of block ``name``."""
        s = self[name]
        return s.stop - s.start

    def index(self, name: str, axis: int) -> int:
        """State index of ``axis`` of block ``name``."""
        return self[name].start + axis

    @property
    def vel(self) -> slice:
        """Slice of the ``vel`` block."""
        return self["vel"]

    @property
    def att(self) -> slice:
        """Slice of the ``att`` block."""
        return self["att"]

    @property
    def accel_bias(self) -> slice:
        """Slice of the ``accel_bias`` block."""
        return self["accel_bias"]

    @property
    def gyro_bias(self) -> slice:
        """Slice of the ``gyro_bias`` block."""
        return self["gyro_bias"]


#: paper 002: horizontal velocity errors and horizontal accelerometer biases
LAYOUT_10 = AlignLayout((("vel", 2), ("att", 3), ("accel_bias", 2), ("gyro_bias", 3)))
#: velocity matching with the vertical channel (PSINS alignvn)
LAYOUT_12 = AlignLayout((("vel", 3), ("att", 3), ("accel_bias", 3), ("gyro_bias", 3)))
