"""MATLAB Fuzzy Logic Toolbox ``.fis`` text files: read and write.

A ``.fis`` file has ``[System]``, ``[InputN]``, ``[OutputN]`` and ``[Rules]`` sections of
``Key=Value`` lines; a rule line is ``i1 i2 ..., o1 ... (weight) : connective`` with
1-based term indices (0: don't care / output not used, negative: NOT; 1 AND, 2 OR).
What ``.fis`` cannot hold is dropped on writing and listed by :func:`dropped_fields`:
output defaults, ``binding``, ``provenance``, ``expected``.  Singleton terms and
negated consequents have no fuzzynav/MATLAB counterpart and are refused.
"""
from __future__ import annotations

import re

from fuzzynav.fuzzy._where import FisError, located
from fuzzynav.fuzzy.membership import SHAPES
from fuzzynav.fuzzy.system import Antecedent, FuzzySystem, Operators, Rule, Term, Variable
from fuzzynav.fileio import write_text_atomic
from fuzzynav.fuzzy.textio import read_text

__all__ = ["read_matlab_fis", "dropped_fields", "matlab_text", "v_index", "write_matlab_fis"]

_FROM_MATLAB = {s.matlab: s.name for s in SHAPES.values() if s.matlab}
_KNOWN_SYSTEM_KEYS = {"Name", "Type", "Version", "NumInputs", "NumOutputs", "NumRules",
                      "AndMethod", "OrMethod", "ImpMethod", "AggMethod", "DefuzzMethod",
                      "DisableStructuralChecks"}
_SECTION = re.compile(r"^\[(System|Input(\d+)|Output(\d+)|Rules)\]$")
_MF_LINE = re.compile(r"^'([^']*)'\s*:\s*'([^']*)'\s*,\s*\[([^\]]*)\]$")
_RULE = re.compile(r"^([-\d\s]+),([-\d\s]+)\(\s*([^)]+?)\s*\)\s*:\s*(\d+)$")


def _numbers(text: str, where, path):
    try:
        return [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        raise FisError(path, where, f"expected numbers, got {text!r}") from None


def _sections(text: str, path):
    """Split into {section: [(line number, key, value)]} and the rule lines."""
    sections, current = {}, None
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith(("%", "#")):
            continue
        m = _SECTION.match(line)
        if m:
            current = m.group(1)
            if current in sections:
                raise FisError(path, f"[{current}] (line {no})", "section appears twice")
            sections[current] = []
            continue
        if current is None:
            raise FisError(path, f"line {no}", f"text before the first section: {line!r}")
        if current == "Rules":
            sections[current].append((no, None, line))
            continue
        key, sep, value = line.partition("=")
        if not sep:
            raise FisError(path, f"[{current}] (line {no})", f"expected Key=Value, got "
                                                              f"{line!r}")
        sections[current].append((no, key.strip(), value.strip()))
    return sections


def _kv(entries, section, path):
    out = {}
    for no, key, value in entries:
        if key in out:
            raise FisError(path, f"[{section}].{key} (line {no})", "key appears twice")
        out[key] = (no, value)
    return out


def _get(kv, key, section, path, unquote=True):
    if key not in kv:
        raise FisError(path, f"[{section}].{key}", "missing")
    no, value = kv[key]
    if unquote:
        if not (len(value) >= 2 and value[0] == value[-1] == "'"):
            raise FisError(path, f"[{section}].{key} (line {no})", f"expected a quoted "
                                                                   f"string, got {value}")
        return value[1:-1]
    return value


def _int(kv, key, section, path):
    value = _get(kv, key, section, path, unquote=False)
    try:
        return int(value)
    except ValueError:
        raise FisError(path, f"[{section}].{key}", f"expected an integer, got {value}") from None


def _variable(section, entries, path):
    kv = _kv(entries, section, path)
    rng = _numbers(_get(kv, "Range", section, path, unquote=False).strip("[]"),
                   f"[{section}].Range", path)
    n = _int(kv, "NumMFs", section, path)
    terms = []
    for k in range(1, n + 1):
        key = f"MF{k}"
        value = _get(kv, key, section, path, unquote=False)
        where = f"[{section}].{key} (line {kv[key][0]})"
        m = _MF_LINE.match(value)
        if not m:
            raise FisError(path, where, f"expected 'name':'type',[params], got {value}")
        name, mtype, params = m.groups()
        if mtype not in _FROM_MATLAB:
            raise FisError(path, where, f"unsupported membership function {mtype!r}; "
                                        f"supported: {', '.join(_FROM_MATLAB)}")
        with located(where, path):
            terms.append(Term(name, _FROM_MATLAB[mtype], tuple(_numbers(params, where, path))))
    with located(f"[{section}]", path):
        return Variable(_get(kv, "Name", section, path), tuple(rng), tuple(terms))


def _rules(entries, fis_inputs, fis_outputs, path):
    rules = []
    for no, _, line in entries:
        where = f"[Rules] line {no}"
        m = _RULE.match(line)
        if not m:
            raise FisError(path, where, f"expected 'i1 i2 ..., o1 ... (weight) : 1|2', got "
                                        f"{line!r}")
        ants = [int(v) for v in m.group(1).split()]
        cons = [int(v) for v in m.group(2).split()]
        if len(ants) != len(fis_inputs) or len(cons) != len(fis_outputs):
            raise FisError(path, where, f"needs {len(fis_inputs)} antecedent and "
                                        f"{len(fis_outputs)} consequent indices")
        antecedents = [Antecedent(v.name, _term_name(v, abs(i), where, path), i < 0)
                       for v, i in zip(fis_inputs, ants) if i != 0]
        consequents = []
        for v, i in zip(fis_outputs, cons):
            if i < 0:
                raise FisError(path, where, "negated consequents are not supported")
            if i:
                consequents.append((v.name, _term_name(v, i, where, path)))
        weight = _numbers(m.group(3), where, path)
        if m.group(4) not in ("1", "2") or len(weight) != 1:
            raise FisError(path, where, "connective must be 1 (and) or 2 (or), one weight")
        with located(where, path):
            rules.append(Rule(tuple(antecedents), tuple(consequents), weight[0],
                              "and" if m.group(4) == "1" else "or"))
    return rules


def _term_name(v, i, where, path):
    if not 1 <= i <= len(v.terms):
        raise FisError(path, where, f"term index {i} out of 1..{len(v.terms)} for {v.name!r}")
    return v.terms[i - 1].name


def read_matlab_fis(path) -> FuzzySystem:
    """Read a MATLAB ``.fis`` file (type-1 Mamdani or Sugeno).

    Errors name the file, the section and key (and line) at fault.
    """
    sections = _sections(read_text(path, "MATLAB .fis file"), path)
    if "System" not in sections:
        raise FisError(path, "[System]", "missing section")
    kv = _kv(sections["System"], "System", path)
    for key in kv:
        if key not in _KNOWN_SYSTEM_KEYS:
            raise FisError(path, f"[System].{key}", "unknown key")
    fis_type = _get(kv, "Type", "System", path).lower()
    if fis_type not in ("mamdani", "sugeno"):
        raise FisError(path, "[System].Type", f"only type-1 mamdani/sugeno are supported, "
                                              f"got {fis_type!r}")
    counts = {k: _int(kv, k, "System", path) for k in ("NumInputs", "NumOutputs")}
    variables = {}
    for kind, n in (("Input", counts["NumInputs"]), ("Output", counts["NumOutputs"])):
        variables[kind] = []
        for i in range(1, n + 1):
            if f"{kind}{i}" not in sections:
                raise FisError(path, f"[{kind}{i}]", "missing section")
            variables[kind].append(_variable(f"{kind}{i}", sections[f"{kind}{i}"], path))
    rules = _rules(sections.get("Rules", []), variables["Input"], variables["Output"], path)
    if "NumRules" in kv and _int(kv, "NumRules", "System", path) != len(rules):
        raise FisError(path, "[System].NumRules", f"says {kv['NumRules'][1]}, the [Rules] "
                                                  f"section has {len(rules)}")
    meth = {k: _get(kv, k, "System", path) for k in ("AndMethod", "OrMethod", "DefuzzMethod")}
    if fis_type == "mamdani":
        ops = Operators(meth["AndMethod"], meth["OrMethod"], _get(kv, "ImpMethod", "System", path),
                        _get(kv, "AggMethod", "System", path), meth["DefuzzMethod"])
    else:
        ops = Operators(meth["AndMethod"], meth["OrMethod"], None, None, meth["DefuzzMethod"])
    with located("[System]", path):
        return FuzzySystem(_get(kv, "Name", "System", path), fis_type, ops,
                           tuple(variables["Input"]), tuple(variables["Output"]), tuple(rules))


def _num(v: float) -> str:
    # shortest round-trip repr, without a trailing ".0" (MATLAB style "[-2 -1 0]")
    text = repr(float(v))
    return text[:-2] if text.endswith(".0") else text


def dropped_fields(fis: FuzzySystem) -> list[str]:
    """Fields of ``fis`` that a ``.fis`` file cannot hold."""
    out = [f"outputs.{v.name}.default" for v in fis.outputs if v.default is not None]
    return out + [k for k in ("binding", "provenance", "expected") if getattr(fis, k)]


def matlab_text(fis: FuzzySystem) -> str:
    """The ``.fis`` text of ``fis`` (see :func:`dropped_fields` for what is lost)."""
    if "'" in fis.name or "\n" in fis.name:
        raise FisError(None, "name", "a .fis system name cannot contain quotes or newlines")
    ops = fis.operators
    lines = ["[System]", f"Name='{fis.name}'", f"Type='{fis.type}'", "Version=2.0",
             f"NumInputs={len(fis.inputs)}", f"NumOutputs={len(fis.outputs)}",
             f"NumRules={len(fis.rules)}", f"AndMethod='{ops.and_}'", f"OrMethod='{ops.or_}'",
             f"ImpMethod='{ops.implication or 'prod'}'",
             f"AggMethod='{ops.aggregation or 'sum'}'", f"DefuzzMethod='{ops.defuzzifier}'"]
    for kind, variables in (("Input", fis.inputs), ("Output", fis.outputs)):
        for i, v in enumerate(variables, 1):
            lines += ["", f"[{kind}{i}]", f"Name='{v.name}'",
                      f"Range=[{_num(v.range[0])} {_num(v.range[1])}]",
                      f"NumMFs={len(v.terms)}"]
            for k, t in enumerate(v.terms, 1):
                if SHAPES[t.mf].matlab is None:
                    raise FisError(None, f"{kind.lower()}s[{i - 1}].terms[{k - 1}].mf",
                                   f"'{t.mf}' has no MATLAB .fis equivalent")
                params = " ".join(_num(p) for p in t.params)
                lines.append(f"MF{k}='{t.name}':'{SHAPES[t.mf].matlab}',[{params}]")
    lines += ["", "[Rules]"]
    for r in fis.rules:
        ants = {a.variable: (v_index(fis.inputs, a.variable, a.term) * (-1 if a.negated else 1))
                for a in r.antecedents}
        cons = dict(r.consequents)
        a_idx = " ".join(str(ants.get(v.name, 0)) for v in fis.inputs)
        c_idx = " ".join(str(v.term_index(cons[v.name]) + 1) if v.name in cons else "0"
                         for v in fis.outputs)
        lines.append(f"{a_idx}, {c_idx} ({_num(r.weight)}) : "
                     f"{1 if r.connective == 'and' else 2}")
    return "\n".join(lines) + "\n"


def v_index(variables, name, term) -> int:
    """1-based index of ``term`` in the variable called ``name``."""
    for v in variables:
        if v.name == name:
            return v.term_index(term) + 1
    raise KeyError(name)


def write_matlab_fis(fis: FuzzySystem, path) -> list[str]:
    """Write ``fis`` as a MATLAB ``.fis`` file atomically; return the dropped fields."""
    write_text_atomic(path, matlab_text(fis), what="rule file")
    return dropped_fields(fis)
