"""Cross-field checks of a FuzzySystem (names used by rules, output shapes, operators).

Paths in the messages are relative to the system document (``rules[3].if.x``); the
loader prefixes them with ``$`` and the file name.
"""
from __future__ import annotations

from fuzzynav.fuzzy._where import fail, located, unique
from fuzzynav.fuzzy.membership import FUZZY_SHAPES, SUGENO_SHAPES, check_params

__all__ = ["check_system"]


def check_system(fis) -> None:
    """Raise :class:`FisError` at the first inconsistency of ``fis``."""
    _check_variables(fis)
    _check_rules(fis)
    _check_defuzzification(fis)


def _check_variables(fis):
    if not fis.inputs:
        fail("inputs", "a system needs at least one input")
    if not fis.outputs:
        fail("outputs", "a system needs at least one output")
    unique([v.name for v in fis.inputs], "inputs", "input")
    unique([v.name for v in fis.outputs], "outputs", "output")
    in_names = {v.name for v in fis.inputs}
    for j, v in enumerate(fis.outputs):
        if v.name in in_names:
            fail(f"outputs[{j}].name", f"{v.name!r} is already the name of an input")
    for i, v in enumerate(fis.inputs):
        if v.default is not None:
            fail(f"inputs[{i}].default", "'default' applies to outputs only")
        for k, t in enumerate(v.terms):
            if t.mf not in FUZZY_SHAPES:
                fail(f"inputs[{i}].terms[{k}].mf",
                     f"'{t.mf}' is a Sugeno output shape, not an input shape")
    for j, v in enumerate(fis.outputs):
        _check_output_terms(fis, j, v)

def _check_output_terms(fis, j: int, v):
    sugeno = fis.type == "sugeno"
    kinds = set()
    for k, t in enumerate(v.terms):
        where = f"outputs[{j}].terms[{k}]"
        if sugeno and t.mf not in SUGENO_SHAPES:
            fail(f"{where}.mf", f"Sugeno outputs use 'constant' or 'linear', got {t.mf!r}")
        if not sugeno and t.mf in SUGENO_SHAPES:
            fail(f"{where}.mf", f"'{t.mf}' is a Sugeno shape; this system is Mamdani")
        if t.mf == "linear":
            with located(where):
                check_params("linear", t.params, len(fis.inputs), "params")
        _check_output_extent(where, v, t)
        kinds.add("singleton" if t.mf == "singleton" else "set")
    if len(kinds) > 1:
        fail(f"outputs[{j}].terms", "an output mixes singleton and continuous terms; "
                                    "use one kind per output")

def _check_output_extent(where: str, v, t):
    lo, hi = v.range
    p = t.params
    if t.mf == "tri" and not p[0] < p[2]:
        fail(f"{where}.params", "an output triangle needs a < c (non-zero width)")
    if t.mf == "trap" and not p[0] < p[3]:
        fail(f"{where}.params", "an output trapezoid needs a < d (non-zero width)")
    if t.mf == "singleton" and not lo <= p[0] <= hi:
        fail(f"{where}.params", f"singleton position {p[0]!r} outside the range "
                                f"[{lo!r}, {hi!r}]")

def _check_rules(fis):
    if not fis.rules:
        fail("rules", "a system needs at least one rule")
    ins = {v.name: v for v in fis.inputs}
    outs = {v.name: v for v in fis.outputs}
    for r, rule in enumerate(fis.rules):
        seen = set()
        for a in rule.antecedents:
            where = f"rules[{r}].if.{a.variable}"
            if a.variable not in ins:
                fail(where, f"unknown input {a.variable!r}; inputs: {', '.join(ins)}")
            if a.variable in seen:
                fail(where, f"input {a.variable!r} appears twice in one rule")
            seen.add(a.variable)
            _check_term(where, "input", ins[a.variable], a.term)
        seen = set()
        for out, term in rule.consequents:
            where = f"rules[{r}].then.{out}"
            if out not in outs:
                fail(where, f"unknown output {out!r}; outputs: {', '.join(outs)}")
            if out in seen:
                fail(where, f"output {out!r} appears twice in one rule")
            seen.add(out)
            _check_term(where, "output", outs[out], term)

def _check_term(where, what, var, term: str):
    names = [t.name for t in var.terms]
    if term not in names:
        fail(where, f"unknown term {term!r} of {what} {var.name!r}; terms: "
                    f"{', '.join(names)}")

def _check_defuzzification(fis):
    if fis.type != "mamdani":
        return
    op = fis.operators
    for j, v in enumerate(fis.outputs):
        kinds = {t.kind for t in v.terms}
        if "singleton" in kinds and op.defuzzifier == "bisector":
            fail("operators.defuzzifier", f"bisector is undefined for the singleton "
                                          f"terms of output {v.name!r}")
        if ("curved" in kinds and op.defuzzifier in ("mom", "som", "lom")
                and op.aggregation != "max"):
            fail("operators.defuzzifier",
                 f"{op.defuzzifier} with {op.aggregation} aggregation needs piecewise-"
                 f"linear output terms (tri, trap); output {v.name!r} has curved terms")
