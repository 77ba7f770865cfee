"""The register-tiled products against numpy and against plain in-order sums.

Every tile entry is one sum in ascending index order, so it must agree with the plain
Python loop to rounding (stated: 1e-14 relative; in practice identical), for every shape:
odd and even row counts, column counts that are and are not multiples of four.
"""
import numpy as np
import pytest

from fuzzynav.filters.tiles import rows_dots

SHAPES = [(1, 1), (2, 3), (3, 4), (5, 7), (9, 15), (10, 19), (15, 15)]


def _close(a, b, rel=1e-14):
    scale = max(np.abs(b).max(), 1e-300)
    assert np.abs(a - b).max() <= rel * scale


@pytest.mark.parametrize("rows, n", SHAPES)
def test_rows_dots_on_a_transposed_view_is_a_times_b(rows, n):
    rng = np.random.default_rng(rows * 100 + n)
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    k_end = max(1, n - 2)
    out = np.full((n, n), np.nan)
    out[:rows] = 0.0
    for i in range(0, rows, 2):
        rows_dots(A[:, :k_end], i, i + 1 < rows, B[:k_end].T, 0, n, out)
    plain = np.array([[sum(A[i, k] * B[k, j] for k in range(k_end)) for j in range(n)]
                      for i in range(rows)])
    _close(out[:rows], plain)
    _close(out[:rows], A[:rows, :k_end] @ B[:k_end], rel=1e-12)
    assert np.isnan(out[rows:]).all()  # rows outside the range are left alone


@pytest.mark.parametrize("two", [False, True])
@pytest.mark.parametrize("n, j0, j1", [(15, 0, 9), (15, 3, 15), (7, 2, 3), (19, 4, 17)])
def test_rows_dots_adds_a_b_transpose_to_the_block(two, n, j0, j1):
    rng = np.random.default_rng(n + j0 + 31 * j1)
    A, B, out0 = rng.normal(size=(n, n)), rng.normal(size=(n, n)), rng.normal(size=(n, n))
    out = out0.copy()
    i = 1
    rows_dots(A, i, two, B, j0, j1, out)
    rows = [i, i + 1] if two else [i]
    expect = out0.copy()
    for r in rows:
        for j in range(j0, j1):
            s = out0[r, j]
            for k in range(n):
                s += A[r, k] * B[j, k]
            expect[r, j] = s
    _close(out, expect)
    np.testing.assert_array_equal(np.delete(out, rows, axis=0), np.delete(out0, rows, axis=0))
