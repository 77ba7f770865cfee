"""n-term triangular partitions (n = 2..9) from ordered breakpoints, with standard labels.

Label families (``labels="signed"``, the default, or ``"magnitude"``), centre-out:

====  ==========================================  =====================================
n     signed                                      magnitude
====  ==========================================  =====================================
2     NS PS                                       S L
3     NS ZE PS                                    S M L
4     NM NS PS PM                                 XS S L XL
5     NM NS ZE PS PM                              XS S M L XL
6     NB NM NS PS PM PB                           XXS XS S L XL XXL
7     NB NM NS ZE PS PM PB                        XXS XS S M L XL XXL
8     NVB NB NM NS PS PM PB PVB                   XXXS XXS XS S L XL XXL XXXL
9     NVB NB NM NS ZE PS PM PB PVB                XXXS XXS XS S M L XL XXL XXXL
====  ==========================================  =====================================

ZE / M exist only for odd n; further terms take the next size outwards (VB = very big).
"""
from __future__ import annotations

import math

from fuzzynav.fuzzy._where import fail, located
from fuzzynav.fuzzy.system import Term

__all__ = ["standard_labels", "triangular_partition"]

_SIGNED = ("NS", "NM", "NB", "NVB")
_MAGNITUDE = ("S", "XS", "XXS", "XXXS")


def standard_labels(n: int, family: str = "signed") -> tuple[str, ...]:
    """The standard labels of an ``n``-term partition (see the module table)."""
    if not 2 <= n <= 9:
        fail("labels", f"a partition has 2 to 9 terms, got {n}")
    if family == "signed":
        neg = _SIGNED[: n // 2]
        pos = tuple("P" + s[1:] for s in neg)
        mid = ("ZE",)
    elif family == "magnitude":
        neg = _MAGNITUDE[: n // 2]
        pos = tuple(s[:-1] + "L" for s in neg)
        mid = ("M",)
    else:
        fail("labels", f"label family must be 'signed' or 'magnitude', got {family!r}")
    return tuple(reversed(neg)) + (mid if n % 2 else ()) + pos


def _labels(n, labels):
    if labels is None or isinstance(labels, str):
        return standard_labels(n, labels or "signed")
    labels = tuple(labels)
    if len(labels) != n:
        fail("labels", f"{n} terms need {n} labels, got {len(labels)}")
    if len(set(labels)) != n:
        fail("labels", f"labels must be unique, got {list(labels)}")
    return labels


def triangular_partition(breakpoints, labels=None, *, strong: bool = True) -> tuple[Term, ...]:
    """Triangular terms covering a variable.

    Parameters
    ----------
    breakpoints : sequence of float, or sequence of (a, b, c)
        ``strong=True``: the n peaks ``p_0 < ... < p_{n-1}`` of a strong (Ruspini)
        partition -- term j is ``tri(p_{j-1}, p_j, p_{j+1})``, the end terms mirrored
        outwards (``tri(2 p_0 - p_1, p_0, p_1)``...), so the degrees sum to 1 on
        ``[p_0, p_{n-1}]``.  ``strong=False``: n free triangles ``(a, b, c)`` with
        ``a <= b <= c`` and non-decreasing peaks ``b``.
    labels : None, "signed", "magnitude" or sequence of str
        Term names: a standard family (default signed) or n user labels.
    strong : bool
        Strong partition from peaks (default) or free triangles.

    Returns
    -------
    tuple of Term
    """
    if strong:
        peaks = [float(p) for p in breakpoints]
        n = len(peaks)
        names = _labels(n, labels) if 2 <= n <= 9 else standard_labels(n)
        for i, p in enumerate(peaks):
            if not math.isfinite(p):
                fail(f"breakpoints[{i}]", f"must be finite, got {p!r}")
            if i and not p > peaks[i - 1]:
                fail(f"breakpoints[{i}]", f"peaks must increase strictly, got {peaks}")
        ext = [2 * peaks[0] - peaks[1]] + peaks + [2 * peaks[-1] - peaks[-2]]
        return tuple(Term(names[j], "tri", (ext[j], ext[j + 1], ext[j + 2]))
                     for j in range(n))
    tris = [tuple(float(v) for v in t) for t in breakpoints]
    n = len(tris)
    names = _labels(n, labels) if 2 <= n <= 9 else standard_labels(n)
    for j, t in enumerate(tris):
        if len(t) != 3:
            fail(f"breakpoints[{j}]", f"a free triangle is (a, b, c), got {t}")
        if j and t[1] < tris[j - 1][1]:
            fail(f"breakpoints[{j}]", "peaks b must not decrease from term to term")
    out = []
    for j, t in enumerate(tris):
        with located(f"breakpoints[{j}]"):
            out.append(Term(names[j], "tri", t))
    return tuple(out)
