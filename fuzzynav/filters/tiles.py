"""Small dense matrix products in register tiles (numba), for the covariance kernels.

The covariance products of a 15- to 30-state filter are too small for BLAS (a call costs more
than the arithmetic) and, written one dot product at a time, latency-bound: each sum waits for
its previous addition.  These kernels compute two rows by four columns at once, eight
independent sums sharing every load, which keeps the floating-point units busy.

Every entry is still one sum in ascending index order, started from the same value, so the
results are bit-for-bit those of plain loops computing one dot product after another; only
the order in which entries are computed changes.  :func:`rows_dots` adds a block of
``A B^T``; given a transposed view ``B.T`` it computes ``A B`` (its loads then run along
the rows of ``B``).
"""
from __future__ import annotations

import numba as nb


@nb.njit(cache=True)
def rows_dots(A, i, two, B, j0, j1, out):
    """``out[r, j] += A[r] . B[j]`` for ``r = i`` (and ``i + 1`` when ``two``), ``j0 <= j < j1``.

    Each sum starts from ``out``'s entry and adds the products in ascending ``k``.
    """
    n = A.shape[1]
    j = j0
    if two:
        while j + 4 <= j1:
            a0, a1, a2, a3 = out[i, j], out[i, j + 1], out[i, j + 2], out[i, j + 3]
            b0, b1, b2, b3 = out[i + 1, j], out[i + 1, j + 1], out[i + 1, j + 2], \
                out[i + 1, j + 3]
            for k in range(n):
                u, v = A[i, k], A[i + 1, k]
                p0, p1, p2, p3 = B[j, k], B[j + 1, k], B[j + 2, k], B[j + 3, k]
                a0 += u * p0
                a1 += u * p1
                a2 += u * p2
                a3 += u * p3
                b0 += v * p0
                b1 += v * p1
                b2 += v * p2
                b3 += v * p3
            out[i, j], out[i, j + 1], out[i, j + 2], out[i, j + 3] = a0, a1, a2, a3
            out[i + 1, j], out[i + 1, j + 1], out[i + 1, j + 2], out[i + 1, j + 3] = \
                b0, b1, b2, b3
            j += 4
        while j < j1:
            a0, b0 = out[i, j], out[i + 1, j]
            for k in range(n):
                p = B[j, k]
                a0 += A[i, k] * p
                b0 += A[i + 1, k] * p
            out[i, j], out[i + 1, j] = a0, b0
            j += 1
        return
    while j + 4 <= j1:
        a0, a1, a2, a3 = out[i, j], out[i, j + 1], out[i, j + 2], out[i, j + 3]
        for k in range(n):
            u = A[i, k]
            a0 += u * B[j, k]
            a1 += u * B[j + 1, k]
            a2 += u * B[j + 2, k]
            a3 += u * B[j + 3, k]
        out[i, j], out[i, j + 1], out[i, j + 2], out[i, j + 3] = a0, a1, a2, a3
        j += 4
    while j < j1:
        a0 = out[i, j]
        for k in range(n):
            a0 += A[i, k] * B[j, k]
        out[i, j] = a0
        j += 1
