"""Random fuzzy-system documents for the tests (plain dicts in the rule-file format)."""
from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
RULES = ROOT / "rules"
DATA = ROOT / "tests" / "data"
GPS = str(RULES / "paper000_gps_sins.json")
ATT = str(RULES / "paper000_attitude.json")
ROR = str(RULES / "paper002_ror.json")
TIPPER = str(DATA / "matlab" / "tipper.fis")

OPS = {"and": "min", "or": "max", "implication": "min", "aggregation": "max",
       "defuzzifier": "centroid"}


def lattice_partition(rng, lo, hi, n, step):
    """A strong triangular partition whose breakpoints lie on ``lo + k * step``."""
    k_max = int(round((hi - lo) / step))
    inner = np.sort(rng.choice(np.arange(1, k_max), size=n - 2, replace=False))
    peaks = np.concatenate([[0], inner, [k_max]]) * step + lo
    ext = np.concatenate([[2 * peaks[0] - peaks[1]], peaks, [2 * peaks[-1] - peaks[-2]]])
    return [{"name": f"T{j}", "mf": "tri", "params": [float(ext[j]), float(ext[j + 1]),
                                                     float(ext[j + 2])]} for j in range(n)]


def free_terms(rng, lo, hi, n, shapes=("tri", "trap"), shoulder_prob=0.15):
    """n random tri/trap terms over [lo, hi] (some degenerate shoulders, some overlap)."""
    w = hi - lo
    terms = []
    for j in range(n):
        shape = shapes[rng.integers(len(shapes))]
        centre = rng.uniform(lo - 0.1 * w, hi + 0.1 * w)
        left, right = rng.uniform(0.05, 0.5, size=2) * w
        if shape == "tri":
            p = [centre - left, centre, centre + right]
            if rng.random() < shoulder_prob:
                p[0 if rng.random() < 0.5 else 2] = centre
        else:
            top = rng.uniform(0.0, 0.3) * w
            p = [centre - left, centre, centre + top, centre + top + right]
            if rng.random() < shoulder_prob:
                p[1] = p[0]
        terms.append({"name": f"T{j}", "mf": shape, "params": [float(v) for v in p]})
    return terms


def random_rules(rng, inputs, out_terms, *, negate_prob=0.0, or_prob=0.0, weight_prob=0.0,
                 dont_care_prob=0.0, max_rules=64):
    """A rule table over all term combinations (a random subset when there are many)."""
    combos = list(itertools.product(*[range(len(v["terms"])) for v in inputs]))
    if len(combos) > max_rules:
        combos = [combos[i] for i in rng.choice(len(combos), max_rules, replace=False)]
    rules = []
    for combo in combos:
        cond = {}
        for v, k in zip(inputs, combo):
            if len(combo) > 1 and rng.random() < dont_care_prob:
                continue
            name = v["terms"][k]["name"]
            cond[v["name"]] = {"not": name} if rng.random() < negate_prob else name
        if not cond:
            cond[inputs[0]["name"]] = inputs[0]["terms"][combo[0]]["name"]
        rule = {"if": cond, "then": {"y": out_terms[rng.integers(len(out_terms))]["name"]},
                "weight": float(rng.uniform(0.2, 1.0)) if rng.random() < weight_prob else 1.0}
        if rng.random() < or_prob:
            rule["connective"] = "or"
        rules.append(rule)
    return rules


def mamdani_doc(inputs, out_terms, rules, ops=None, out_range=(0.0, 1.0), name="random"):
    """Assemble a Mamdani document with one output ``y``."""
    return {"format": "fuzzynav-fis", "version": 1, "name": name, "type": "mamdani",
            "operators": dict(OPS, **(ops or {})), "inputs": inputs,
            "outputs": [{"name": "y", "range": list(out_range), "terms": out_terms}],
            "rules": rules}


def random_mamdani(rng, *, n_inputs, n_terms, n_out_terms, ops=None, out_shapes=("tri",),
                   **rule_kw):
    """A random Mamdani document on inputs [-1, 1] (strong partitions), output [0, 1]."""
    inputs = [{"name": f"x{i}", "range": [-1.0, 1.0],
               "terms": lattice_partition(rng, -1.0, 1.0, n_terms, 0.01)}
              for i in range(n_inputs)]
    out_terms = free_terms(rng, 0.0, 1.0, n_out_terms, out_shapes)
    return mamdani_doc(inputs, out_terms, random_rules(rng, inputs, out_terms, **rule_kw), ops)
