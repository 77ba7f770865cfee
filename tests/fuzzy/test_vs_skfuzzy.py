"""Against scikit-fuzzy on random Mamdani systems (min/max, clip implication).

The scikit-fuzzy systems are built here directly from the documents with skfuzzy's own
membership functions (not through fuzzynav's exporter).  Input breakpoints lie on the
input universes' grid so that skfuzzy's interpolated fuzzification is exact; the output
universe is fine (4 001 points), which bounds skfuzzy's own error well below 1e-3.
"""
import numpy as np
import pytest
import skfuzzy
from skfuzzy import control as ctrl

from fuzzynav.fuzzy import load_fis, to_skfuzzy
from tests.fuzzy.systems import random_mamdani

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:skfuzzy")

N_SYSTEMS = 104
DEFUZZ = ("centroid", "centroid", "bisector", "mom", "som", "lom")
SK_MF = {"tri": skfuzzy.trimf, "trap": skfuzzy.trapmf}


def _sk_system(doc, n_in_points=2001, n_out_points=4001):
    variables = {}
    for v in doc["inputs"] + doc["outputs"]:
        is_out = v in doc["outputs"]
        n = n_out_points if is_out else n_in_points
        universe = np.linspace(v["range"][0], v["range"][1], n)
        if is_out:
            var = ctrl.Consequent(universe, v["name"],
                                  defuzzify_method=doc["operators"]["defuzzifier"])
        else:
            var = ctrl.Antecedent(universe, v["name"])
        for t in v["terms"]:
            var[t["name"]] = SK_MF[t["mf"]](universe, t["params"])
        variables[v["name"]] = var
    rules = []
    for r in doc["rules"]:
        terms = [variables[k][c] for k, c in r["if"].items()]
        expr = terms[0]
        for t in terms[1:]:
            expr = expr & t
        rules.append(ctrl.Rule(expr, [variables[o][t] for o, t in r["then"].items()]))
    return ctrl.ControlSystemSimulation(ctrl.ControlSystem(rules))


def _systems():
    rng = np.random.default_rng(20260214)
    for k in range(N_SYSTEMS):
        n_in = 2 if k % 3 else 3
        n_terms = int(rng.integers(3, 8 if n_in == 2 else 5))
        # scikit-fuzzy builds its rule graph in O(rules^2): larger tables are subsampled
        yield k, rng, random_mamdani(rng, n_inputs=n_in, n_terms=n_terms,
                                     n_out_terms=int(rng.integers(3, 8)),
                                     ops={"defuzzifier": DEFUZZ[k % len(DEFUZZ)]},
                                     max_rules=20)


@pytest.mark.parametrize("chunk", range(4))
def test_random_mamdani_systems_agree_with_skfuzzy(chunk):
    checked = 0
    for k, rng, doc in _systems():
        if k % 4 != chunk:
            continue
        fis = load_fis(doc)
        sim = _sk_system(doc)
        X = rng.uniform(-1.0, 1.0, (3, len(doc["inputs"])))
        ours, info = fis.evaluate({n: X[:, i] for i, n in enumerate(fis.input_names)},
                                  return_info=True)
        fired = info.status == 0  # skfuzzy raises when no rule fires
        for row, value in zip(X[fired], ours["y"][fired]):
            for name, x in zip(fis.input_names, row):
                sim.input[name] = x
            sim.compute()
            assert abs(sim.output["y"] - value) <= 1e-3, (k, doc["operators"], row)
            checked += 1
    assert checked >= N_SYSTEMS // 2


def test_exporter_matches_the_direct_skfuzzy_build():
    rng = np.random.default_rng(7)
    for k in range(3):
        doc = random_mamdani(rng, n_inputs=2, n_terms=3, n_out_terms=4,
                             ops={"defuzzifier": "centroid"}, negate_prob=0.2,
                             weight_prob=0.5, or_prob=0.3)
        fis = load_fis(doc)
        sim = ctrl.ControlSystemSimulation(to_skfuzzy(fis, 20001))
        for row in rng.uniform(-1, 1, (3, 2)):
            for name, x in zip(fis.input_names, row):
                sim.input[name] = x
            sim.compute()
            ours = fis.evaluate(dict(zip(fis.input_names, row)))["y"]
            assert abs(sim.output["y"] - ours) <= 1e-3


@pytest.mark.parametrize("ops,where", [({"implication": "prod"}, "operators.implication"),
                                       ({"aggregation": "sum"}, "operators.aggregation")])
def test_exporter_refuses_what_skfuzzy_cannot_do(ops, where):
    from fuzzynav.fuzzy import FisError

    doc = random_mamdani(np.random.default_rng(1), n_inputs=1, n_terms=3, n_out_terms=3,
                         ops=ops)
    with pytest.raises(FisError) as exc:
        to_skfuzzy(load_fis(doc))
    assert exc.value.where == where
