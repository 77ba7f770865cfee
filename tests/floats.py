"""Comparing floats that two different evaluation paths computed.

Two paths that compute the same quantity with the same operations in a different order — a
batch of samples against one sample, a matrix product against a loop, a compiled kernel
against numpy — agree to rounding, not to the bit, and which bits differ depends on the
machine:

* BLAS (numpy's ``@``; OpenBLAS with ``DYNAMIC_ARCH``) picks its kernel per CPU *and* per
  matrix shape, so ``mu @ grid`` sums a row in another order for 1 row than for 3 rows;
* numpy's ``sum`` is pairwise with an 8-way unrolled inner block, so the order of additions
  depends on the array length and on where a reduction starts;
* numpy's SIMD transcendental functions (``exp``, ``sin``, ...) may differ by an ulp or so
  between CPUs with different vector units, and between contiguous and strided inputs.

Such comparisons use :data:`ULP_RTOL` (a few ulp of the result) or a rounding bound stated
where they are made.  The same path with the same inputs (same seed → same data, a file
written and read back, the same kernel on the same arguments) is compared exactly: there,
bit-identity is the property under test.
"""
from __future__ import annotations

import numpy as np
import pytest

#: a few ulp, relative: the same operations done in another order
ULP_RTOL = 4 * np.finfo(float).eps


def sum_order_rtol(n_terms: int) -> float:
    """Relative bound between two summation orders of ``n_terms`` non-negative terms.

    Any order of summing ``n`` non-negative floats is within ``(n - 1) eps`` (relative) of the
    exact sum (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., §4.2), so two
    orders differ by at most twice that; a ratio of two such sums (a centroid) by twice again.
    """
    return 4.0 * max(n_terms - 1, 1) * np.finfo(float).eps


def assert_same_up_to_rounding(actual, desired, rtol: float = ULP_RTOL):
    """``actual`` equals ``desired`` up to ``rtol`` (NaN where the other is NaN)."""
    np.testing.assert_allclose(actual, desired, rtol=rtol, atol=0.0)


#: a run scored chunk by chunk against the whole run scored at once: the same sums
#: (fuzzynav.block_sums), equal to the last bit on the machines measured, but the errors
#: summed are formed on other slices of the arrays (numpy's vectorised loops): held to this
METRICS_RTOL = 1e-12


def same_metrics(got: dict, ref: dict, rtol: float = METRICS_RTOL) -> None:
    """Two paths' metrics: the same names in the same order, each value within ``rtol``
    (NaN where the other is NaN)."""
    assert list(got) == list(ref)
    for k, v in ref.items():
        assert got[k] == pytest.approx(v, rel=rtol, abs=0.0, nan_ok=True), k
