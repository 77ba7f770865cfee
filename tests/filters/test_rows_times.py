"""The register-tiled product :func:`fuzzynav.filters.sized.rows_times` against numpy and
against plain in-order sums.

Every tile entry is one sum in ascending index order, so it must agree with the plain
Python loop to rounding (stated: 1e-14 relative; in practice identical), for every shape:
odd and even row counts, column counts that are and are not multiples of four, inner
lengths shorter than the row.
"""
import numba as nb
import numpy as np
import pytest

from fuzzynav.filters import sized

SHAPES = [(1, 1), (2, 3), (3, 4), (5, 7), (9, 15), (10, 19), (15, 15)]


@nb.njit
def _rows(A, B, rows, K, n, out):
    for i in range(0, rows, 2):
        sized.rows_times(A, B, i, i + 1 if i + 1 < rows else i, K, n, out)


def _close(a, b, rel=1e-14):
    scale = max(np.abs(b).max(), 1e-300)
    assert np.abs(a - b).max() <= rel * scale


@pytest.mark.parametrize("rows, n", SHAPES)
def test_rows_times_is_a_times_b_over_the_first_k_columns(rows, n):
    rng = np.random.default_rng(rows * 100 + n)
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    K = max(1, n - 2)
    out = np.full((n, n), np.nan)
    _rows(A, B, rows, K, n, out)
    plain = np.array([[sum(A[i, k] * B[k, j] for k in range(K)) for j in range(n)]
                      for i in range(rows)])
    _close(out[:rows], plain)
    _close(out[:rows], A[:rows, :K] @ B[:K], rel=1e-12)
    assert np.isnan(out[rows:]).all()  # rows outside the range are left alone
