"""MATLAB-sampled mode: published evalfis results and the Σµx/Σµ definition on 101 points."""
import zlib

import numpy as np
import pytest
import skfuzzy

from fuzzynav.fuzzy import load_fis, read_matlab_fis
from tests.floats import assert_same_up_to_rounding
from tests.fuzzy.reference import firing
from tests.fuzzy.systems import TIPPER, random_mamdani



@pytest.mark.parametrize("service,food,published", [
    (2, 1, 7.0169), (4, 5, 14.4585), (7, 8, 20.3414),  # MATLAB evalfis documentation
])
def test_tipper_reproduces_matlab_evalfis(service, food, published):
    fis = read_matlab_fis(TIPPER)
    tip = fis.evaluate({"service": service, "food": food}, mode="sampled")["tip"]
    assert tip == pytest.approx(published, abs=5e-5)


def test_tipper_reproduces_fuzzyr_evalfis():
    # the R package FuzzyR (a port of the MATLAB toolbox) documents 5.558586 at (1, 2)
    fis = read_matlab_fis(TIPPER)
    assert fis.evaluate({"service": 1, "food": 2}, mode="sampled")["tip"] == pytest.approx(
        5.558586, abs=5e-7)


def _matlab_defuzz(x, mu, method):
    # straight transcriptions of the definitions, one sample at a time
    total = mu.sum()
    if method == "centroid":
        return float(np.sum(mu * x) / total)
    if method == "bisector":
        acc = 0.0
        for k in range(len(x)):
            acc += mu[k]
            if acc >= total / 2:
                return float(x[k])
    at = x[mu == mu.max()]
    return float({"mom": np.mean, "som": np.min, "lom": np.max}[method](at))


def _sampled_reference(doc, inputs, n_points):
    out = doc["outputs"][0]
    ops = doc["operators"]
    x = np.linspace(out["range"][0], out["range"][1], n_points)
    mf = {t["name"]: {"tri": skfuzzy.trimf, "trap": skfuzzy.trapmf}[t["mf"]](x, t["params"])
          for t in out["terms"]}
    mu = np.zeros(n_points)
    for w, rule in zip(firing(doc, inputs), doc["rules"]):
        imp = np.minimum(w, mf[rule["then"]["y"]]) if ops["implication"] == "min" else \
            w * mf[rule["then"]["y"]]
        mu = {"max": np.maximum(mu, imp), "sum": mu + imp, "probor": mu + imp - mu * imp}[
            ops["aggregation"]]
    return _matlab_defuzz(x, mu, ops["defuzzifier"])


@pytest.mark.parametrize("defuzz", ("centroid", "bisector", "mom", "som", "lom"))
@pytest.mark.parametrize("imp,agg", [("min", "max"), ("prod", "sum"), ("min", "probor")])
def test_sampled_mode_is_the_matlab_definition(defuzz, imp, agg):
    rng = np.random.default_rng(zlib.crc32(f"{defuzz}{imp}{agg}".encode()))
    for n_points in (101, 50):
        doc = random_mamdani(rng, n_inputs=2, n_terms=3, n_out_terms=4,
                             out_shapes=("tri", "trap"),
                             ops={"implication": imp, "aggregation": agg, "defuzzifier": defuzz})
        fis = load_fis(doc)
        X = rng.uniform(-1, 1, (8, 2))
        got = fis.evaluate({"x0": X[:, 0], "x1": X[:, 1]}, mode="sampled",
                           n_points=n_points)["y"]
        ref = [_sampled_reference(doc, {"x0": a, "x1": b}, n_points) for a, b in X]
        np.testing.assert_allclose(got, ref, rtol=1e-14, atol=1e-14)


def test_sampled_sugeno_equals_exact():
    fis = load_fis({
        "format": "fuzzynav-fis", "version": 1, "name": "s", "type": "sugeno",
        "operators": {"and": "min", "or": "max", "defuzzifier": "wtaver"},
        "inputs": [{"name": "x", "range": [0, 1], "terms": [
            {"name": "lo", "mf": "gauss", "params": [0.3, 0.0]},
            {"name": "hi", "mf": "gauss", "params": [0.3, 1.0]}]}],
        "outputs": [{"name": "y", "range": [0, 5], "terms": [
            {"name": "a", "mf": "linear", "params": [2.0, 1.0]},
            {"name": "b", "mf": "constant", "params": [4.0]}]}],
        "rules": [{"if": {"x": "lo"}, "then": {"y": "a"}},
                  {"if": {"x": "hi"}, "then": {"y": "b"}}]})
    x = np.linspace(0, 1, 7)
    # Sugeno outputs are not sampled: the sampled mode's numpy path against the exact mode's
    # compiled kernel, the same weighted average summed in another order: to rounding
    assert_same_up_to_rounding(fis.evaluate({"x": x}, mode="sampled")["y"],
                               fis.evaluate({"x": x})["y"])
