"""Membership shapes: numpy and numba versions against scikit-fuzzy, edges, validation."""
import numpy as np
import pytest
import skfuzzy

from fuzzynav.fuzzy import FisError, Term
from fuzzynav.fuzzy.membership import SHAPES, evaluate_mf, mf_scalar

SK = {"tri": skfuzzy.trimf, "trap": skfuzzy.trapmf,
      "gauss": lambda x, p: skfuzzy.gaussmf(x, p[1], p[0]),
      "gauss2": lambda x, p: skfuzzy.gauss2mf(x, p[1], p[0], p[3], p[2]),
      "gbell": lambda x, p: skfuzzy.gbellmf(x, *p),
      "sigmoid": lambda x, p: skfuzzy.sigmf(x, p[1], p[0]),
      "smf": lambda x, p: skfuzzy.smf(x, *p), "zmf": lambda x, p: skfuzzy.zmf(x, *p),
      "pimf": lambda x, p: skfuzzy.pimf(x, *p)}


def _random_params(rng, mf):
    c = rng.uniform(-1, 1)
    s = rng.uniform(0.1, 1)
    return {"tri": sorted(rng.uniform(-2, 2, 3)), "trap": sorted(rng.uniform(-2, 2, 4)),
            "gauss": [s, c], "gauss2": [s, c - 0.3, 0.5 * s, c + 0.3],
            "gbell": [s, rng.uniform(0.5, 3), c], "sigmoid": [rng.uniform(-10, 10), c],
            "smf": sorted(rng.uniform(-2, 2, 2)), "zmf": sorted(rng.uniform(-2, 2, 2)),
            "pimf": sorted(rng.uniform(-2, 2, 4))}[mf]


@pytest.mark.parametrize("mf", sorted(SK))
def test_shapes_match_skfuzzy_and_the_numba_version(mf):
    rng = np.random.default_rng(len(mf))
    for _ in range(20):
        p = [float(v) for v in _random_params(rng, mf)]
        x = np.concatenate([rng.uniform(-3, 3, 200), p])  # breakpoints included
        ours = evaluate_mf(mf, p, x)
        np.testing.assert_allclose(ours, SK[mf](x, p), rtol=1e-12, atol=1e-14)
        fp = np.array(p)
        scalar = [mf_scalar(SHAPES[mf].code, fp, 0, v) for v in x]
        np.testing.assert_allclose(scalar, ours, rtol=1e-13, atol=1e-15)
        assert ((ours >= 0) & (ours <= 1)).all()


@pytest.mark.parametrize("mf,params,x,expected", [
    ("tri", [0, 0, 1], [-1e-12, 0, 0.25, 1], [0, 1, 0.75, 0]),      # left shoulder (MATLAB)
    ("tri", [0, 1, 1], [0, 0.5, 1, 1 + 1e-12], [0, 0.5, 1, 0]),     # right shoulder
    ("trap", [0, 0, 1, 1], [-1e-12, 0, 0.5, 1, 1.1], [0, 1, 1, 1, 0]),  # rectangle
    ("smf", [1, 1], [0.5, 1, 2], [0, 1, 1]),                          # step (a == b)
    ("zmf", [1, 1], [0.5, 1, 2], [1, 1, 0]),
    ("singleton", [0.3], [0.3, 0.30000001], [1, 0]),
    ("sigmoid", [800.0, 0.0], [-5.0, 5.0], [0, 1]),                   # no overflow
])
def test_edge_values(mf, params, x, expected):
    got = evaluate_mf(mf, params, np.array(x, dtype=float))
    np.testing.assert_allclose(got, expected, atol=1e-12)
    fp = np.array(params, dtype=float)
    np.testing.assert_allclose([mf_scalar(SHAPES[mf].code, fp, 0, v) for v in x], expected,
                               atol=1e-12)


@pytest.mark.parametrize("mf,params,where,match", [
    ("tri", [0, 2, 1], "params", "a <= b <= c"),
    ("trap", [0, 1], "params", "takes 4 parameters"),
    ("gauss", [-1, 0], "params[0]", "sigma must be > 0"),
    ("gbell", [1, 0, 0], "params[1]", "b must be > 0"),
    ("tri", [0, float("nan"), 1], "params[1]", "finite"),
    ("blob", [0], "mf", "unknown membership function 'blob'"),
])
def test_term_validation_names_the_field(mf, params, where, match):
    with pytest.raises(FisError, match=match) as exc:
        Term("A", mf, tuple(params))
    assert exc.value.where == where
