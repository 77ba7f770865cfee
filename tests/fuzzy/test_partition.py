"""Triangular partitions: labels, the strong (Ruspini) property, free triangles, errors."""
import numpy as np
import pytest

from fuzzynav.fuzzy import (FisError, FuzzySystem, Operators, Rule, Antecedent, Variable,
                            standard_labels, triangular_partition)
from fuzzynav.fuzzy.membership import evaluate_mf


def test_standard_labels_of_the_issue():
    assert standard_labels(3) == ("NS", "ZE", "PS")
    assert standard_labels(5) == ("NM", "NS", "ZE", "PS", "PM")
    assert standard_labels(7) == ("NB", "NM", "NS", "ZE", "PS", "PM", "PB")
    assert standard_labels(5, "magnitude") == ("XS", "S", "M", "L", "XL")
    for n in range(2, 10):
        for family in ("signed", "magnitude"):
            labels = standard_labels(n, family)
            assert len(labels) == n == len(set(labels))
            assert (("ZE" in labels) or ("M" in labels)) == (n % 2 == 1)


@pytest.mark.parametrize("n", range(2, 10))
def test_strong_partition_sums_to_one_and_peaks_at_breakpoints(n):
    rng = np.random.default_rng(n)
    peaks = np.sort(rng.uniform(-3, 5, n))
    terms = triangular_partition(peaks)
    x = np.concatenate([np.linspace(peaks[0], peaks[-1], 1001), peaks])
    mu = np.array([evaluate_mf(t.mf, t.params, x) for t in terms])
    np.testing.assert_allclose(mu.sum(axis=0), 1.0, atol=1e-12)
    for j, t in enumerate(terms):
        assert evaluate_mf(t.mf, t.params, [peaks[j]])[0] == 1.0
    assert [t.name for t in terms] == list(standard_labels(n))


def test_free_triangles_and_user_labels():
    terms = triangular_partition([(0, 0, 1), (0, 1, 3), (2, 3, 3)], ["lo", "mid", "hi"],
                                 strong=False)
    assert [t.params for t in terms] == [(0, 0, 1), (0, 1, 3), (2, 3, 3)]
    assert [t.name for t in terms] == ["lo", "mid", "hi"]
    v = Variable("x", (0, 3), terms)
    out = Variable("y", (0, 1), triangular_partition([0, 0.5, 1], "magnitude"))
    rules = [Rule((Antecedent("x", a),), (("y", b),)) for a, b in
             (("lo", "S"), ("mid", "M"), ("hi", "L"))]
    fis = FuzzySystem("p", "mamdani", Operators(), (v,), (out,), tuple(rules))
    assert fis.evaluate({"x": 1.0})["y"] == pytest.approx(0.5)


@pytest.mark.parametrize("args,kw,match", [
    (([0.0],), {}, "2 to 9 terms"),
    ((list(range(10)),), {}, "2 to 9 terms"),
    (([0, 1, 1],), {}, "increase strictly"),
    (([0, 1, 2], ["a", "b"]), {}, "3 terms need 3 labels"),
    (([0, 1, 2], ["a", "b", "a"]), {}, "unique"),
    (([(0, 2, 1), (1, 2, 3)],), {"strong": False}, "a <= b <= c"),
    (([(0, 2, 3), (0, 1, 3)],), {"strong": False}, "must not decrease"),
    (([0, 1, 2], "greek"), {}, "label family"),
])
def test_partition_errors(args, kw, match):
    with pytest.raises(FisError, match=match):
        triangular_partition(*args, **kw)
