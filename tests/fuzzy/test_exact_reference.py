"""Exact modes (compiled kernel and Python path) against the brute-force reference."""
import zlib

import numpy as np
import pytest

from fuzzynav.fuzzy import load_fis
from tests.fuzzy.reference import reference_value
from tests.fuzzy.systems import mamdani_doc, random_mamdani, random_rules

DEFUZZ = ("centroid", "bisector", "mom", "som", "lom")
PWL_COMBOS = [(imp, agg, d) for imp in ("min", "prod") for agg in ("max", "sum", "probor")
              for d in DEFUZZ]
TOL = 1e-9  # output range width is 1


def _rng(*key):
    return np.random.default_rng(zlib.crc32(repr(key).encode()))


def _check(doc, X, engines=("compiled", "python")):
    fis = load_fis(doc)
    names = fis.input_names
    ref = np.array([reference_value(doc, dict(zip(names, row))) for row in X])
    for engine in engines:
        got = fis.evaluate({n: X[:, i] for i, n in enumerate(names)}, engine=engine)["y"]
        np.testing.assert_allclose(got, ref, rtol=0, atol=TOL, err_msg=engine)


@pytest.mark.parametrize("imp,agg,defuzz", PWL_COMBOS)
def test_piecewise_linear_sets_match_brute_force(imp, agg, defuzz):
    rng = _rng(imp, agg, defuzz)
    for _ in range(3):
        n_in = int(rng.integers(1, 3))
        doc = random_mamdani(rng, n_inputs=n_in, n_terms=int(rng.integers(2, 6)),
                             n_out_terms=int(rng.integers(2, 6)), out_shapes=("tri", "trap"),
                             ops={"implication": imp, "aggregation": agg,
                                  "defuzzifier": defuzz, "and": "min" if rng.random() < 0.5
                                  else "prod", "or": "max" if rng.random() < 0.5 else "probor"},
                             negate_prob=0.15, or_prob=0.2, weight_prob=0.3,
                             dont_care_prob=0.2)
        _check(doc, rng.uniform(-1.1, 1.1, (6, n_in)))


def _curved_terms(rng, n):
    shapes = []
    for j in range(n):
        c = rng.uniform(0.0, 1.0)
        s = rng.uniform(0.05, 0.3)
        kind = ["gauss", "gauss2", "gbell", "sigmoid", "smf", "zmf", "pimf", "tri"][j % 8]
        params = {"gauss": [s, c], "gauss2": [s, c - 0.1, 0.5 * s, c + 0.1],
                  "gbell": [s, rng.uniform(1.0, 3.0), c],
                  "sigmoid": [rng.choice([-1, 1]) * rng.uniform(5, 30), c],
                  "smf": [c - s, c + s], "zmf": [c - s, c + s],
                  "pimf": [c - 2 * s, c - s, c + s, c + 2 * s], "tri": [c - s, c, c + s]}[kind]
        shapes.append({"name": f"T{j}", "mf": kind, "params": [float(p) for p in params]})
    return shapes


@pytest.mark.parametrize("imp,agg,defuzz", [
    ("min", "max", "centroid"), ("prod", "max", "bisector"), ("min", "sum", "centroid"),
    ("prod", "probor", "centroid"), ("min", "probor", "bisector"), ("min", "max", "mom"),
    ("prod", "max", "som"), ("min", "max", "lom")])
def test_curved_sets_match_brute_force(imp, agg, defuzz):
    rng = _rng("curved", imp, agg, defuzz)
    for _ in range(2):
        doc = random_mamdani(rng, n_inputs=1, n_terms=3, n_out_terms=3)
        out_terms = _curved_terms(rng, int(rng.integers(2, 5)))
        rng.shuffle(out_terms)
        doc = mamdani_doc(doc["inputs"], out_terms, random_rules(rng, doc["inputs"], out_terms),
                          {"implication": imp, "aggregation": agg, "defuzzifier": defuzz})
        assert not load_fis(doc).is_compilable
        _check(doc, rng.uniform(-1.0, 1.0, (3, 1)), engines=("python",))
