"""Sums over a stream of chunks that do not depend on where the chunks were cut.

A run scored chunk by chunk must report the metrics of the same run scored whole, to the
last bit, or a streamed study and a whole one rank their trials differently by rounding.
Summing each chunk and adding the chunks' sums does not give that: where the chunks are
cut changes the order of the additions.  :class:`BlockSums` cuts the columns into blocks of
:data:`BLOCK_COLUMNS` counted from the first column ever added, sums each block pairwise
(``np.sum`` of a contiguous row) and adds the blocks' sums in order.  A chunk boundary
inside a block only makes it wait for its remaining columns, so any chunking -- one chunk
included -- performs the same additions in the same order.

A whole row of no more than :data:`BLOCK_COLUMNS` columns is summed exactly as ``np.sum``
sums it (``0.0 + s`` is ``s``), so short runs keep the figures they had before the blocks.
"""
from __future__ import annotations

import numpy as np

__all__ = ["BLOCK_COLUMNS", "BlockSums"]

#: columns per block: a run's outputs up to this many rows (1.8 h at 10 Hz) are summed as
#: one pairwise ``np.sum``; a block waiting for its columns holds at most this many
BLOCK_COLUMNS = 2 ** 16


class BlockSums:
    """Row sums of ``(rows, n)`` arrays added one after another (module docstring).

    Parameters
    ----------
    rows : int
        Rows of every array added.
    block : int, optional
        Columns per block; default :data:`BLOCK_COLUMNS` (read when made: tests set it
        smaller to cross many blocks).
    """

    def __init__(self, rows: int, block: int | None = None):
        block = BLOCK_COLUMNS if block is None else block
        if int(block) != block or block < 1:
            raise ValueError(f"block must be a positive number of columns, got {block!r}")
        self.rows, self.block = int(rows), int(block)
        self.n = 0                    # columns added
        self._done = np.zeros(self.rows)
        self._waiting: list = []     # copies of the columns of the block being filled
        self._n_waiting = 0

    def add(self, q: np.ndarray, own: bool = False) -> None:
        """Add the next columns, ``q`` of shape ``(rows, n)``.

        ``own``: the caller hands ``q`` over (it will not change it), so columns left
        waiting for their block are kept as they are, not copied.
        """
        if q.ndim != 2 or q.shape[0] != self.rows:
            raise ValueError(f"expected {self.rows} rows, got an array of shape {q.shape}")
        n, i = q.shape[1], 0
        self.n += n
        if self._n_waiting:
            i = min(n, self.block - self._n_waiting)
            self._wait(q[:, :i], own)
            if self._n_waiting == self.block:
                self._done += self._waiting_sums()
                self._waiting, self._n_waiting = [], 0
        while n - i >= self.block:   # whole blocks straight from q: contiguous rows
            self._done += q[:, i:i + self.block].sum(axis=1)
            i += self.block
        if i < n:
            self._wait(q[:, i:], own)

    def _wait(self, cols: np.ndarray, own: bool) -> None:
        self._waiting.append(cols if own else np.array(cols, order="C"))
        self._n_waiting += cols.shape[1]

    def _waiting_sums(self) -> np.ndarray:
        cols = self._waiting[0] if len(self._waiting) == 1 else \
            np.concatenate(self._waiting, axis=1)
        return cols.sum(axis=1)

    def sums(self) -> np.ndarray:
        """The row sums of every column added, shape ``(rows,)`` (zeros before any)."""
        if not self._n_waiting:
            return self._done.copy()
        return self._done + self._waiting_sums()
