"""Chunk-independent sums (fuzzynav.block_sums): any chunking performs the same additions
as one chunk, so the results are equal to the last bit; against closed forms and np.sum."""
import numpy as np
import pytest

from fuzzynav import block_sums
from fuzzynav.block_sums import BlockSums
from tests.floats import sum_order_rtol


def _fed(q, cuts, block=None, own=False):
    acc = BlockSums(q.shape[0], block)
    for piece in np.split(q, cuts, axis=1):
        acc.add(np.array(piece) if own else piece, own=own)   # own: a piece handed over
    return acc


@pytest.mark.parametrize("block", [1, 7, 64, None])
def test_every_chunking_gives_the_one_chunk_sums_to_the_bit(block):
    rng = np.random.default_rng(4)
    n = 3 * block + 5 if block else 2 * block_sums.BLOCK_COLUMNS + 1234
    q = rng.lognormal(0.0, 3.0, (4, n))   # terms of very different sizes: order matters
    whole = _fed(q, [], block)
    assert whole.n == n
    size = whole.block
    for trial in range(12):
        cuts = np.sort(rng.integers(0, n, rng.integers(1, 40)))
        if trial == 0:   # cuts on the blocks' edges and on either side of them
            cuts = np.array([size - 1, size, size + 1, 2 * size])
        for own in (False, True):
            np.testing.assert_array_equal(_fed(q, cuts, block, own).sums(), whole.sums())
    # and the sums are the sums: an independent order within its rounding bound
    np.testing.assert_allclose(whole.sums(), q.sum(axis=1), rtol=sum_order_rtol(n), atol=0)


def test_the_rule_written_out_blocks_summed_pairwise_and_added_in_order():
    rng = np.random.default_rng(9)
    q = rng.lognormal(0.0, 2.0, (3, 250))
    want = np.zeros(3)
    for a in range(0, 250, 100):          # blocks of 100 from the first column
        want = want + np.array([np.sum(np.ascontiguousarray(r[a:a + 100])) for r in q])
    np.testing.assert_array_equal(_fed(q, [30, 31, 199], 100).sums(), want)


def test_a_row_no_longer_than_a_block_is_np_sum():
    q = np.random.default_rng(2).normal(size=(2, 5000)) ** 2
    got = _fed(q, [1, 4999]).sums()
    assert got.tolist() == [float(np.sum(q[0])), float(np.sum(q[1]))]


def test_integer_sums_are_exact():
    # integers below 2^53 add exactly in any order: the closed form n (n + 1) / 2
    n = 100_001
    q = np.arange(1.0, n + 1.0)[None, :]
    assert _fed(q, [10, 5000, 70000], 999).sums()[0] == n * (n + 1) / 2


def test_nothing_added_is_zero_and_bad_shapes_are_refused():
    acc = BlockSums(3, 8)
    assert acc.sums().tolist() == [0.0, 0.0, 0.0] and acc.n == 0
    acc.add(np.ones((3, 0)))
    assert acc.n == 0
    with pytest.raises(ValueError, match="expected 3 rows, got an array of shape"):
        acc.add(np.ones((2, 4)))
    for bad in (0, 2.5, -3):
        with pytest.raises(ValueError, match="block must be a positive number of columns"):
            BlockSums(3, bad)


def test_the_callers_array_may_change_after_adding():
    q = np.ones((1, 10))
    acc = BlockSums(1, 4)
    acc.add(q)         # 4 + 4 summed, 2 waiting: a copy of them, not a view
    q[:] = 100.0
    assert acc.sums()[0] == 10.0
