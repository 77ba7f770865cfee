"""Rule files: JSON format ``fuzzynav-fis`` version 1 (load, validate, save).

Loading reads at most :data:`MAX_FILE_BYTES`, parses strict JSON (duplicate keys are an
error), checks ``format``/``version`` first (an unknown version is never guessed), then
the shipped JSON Schema (``schema.json``), then the semantics (parameter counts and
order, names used by rules...).  Every error is one :class:`FisError` naming the file
and the JSON path.  Nothing in a file is ever executed.
"""
from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from functools import lru_cache
from importlib import resources

from fuzzynav.errors import MAX_QUOTE, brief
from fuzzynav.fuzzy._where import FisError, located
from fuzzynav.fuzzy.document import FORMAT, OPTIONAL_OBJECTS, VERSION, to_dict
from fuzzynav.fuzzy.fis_matlab import read_matlab_fis, write_matlab_fis
from fuzzynav.fuzzy.system import (NAME_RE, Antecedent, FuzzySystem, Operators, Rule, Term,
                                   Variable)
from fuzzynav.fileio import write_text_atomic
from fuzzynav.fuzzy.textio import MAX_FILE_BYTES, read_text


# ------------------------------------------------------------------------ parsing
class _DupDict(dict):
    """A JSON object in which some keys appeared twice (reported with its path)."""

    dups: tuple = ()


def _pairs(pairs):
    d = dict(pairs)
    if len(d) == len(pairs):
        return d
    seen, dups = set(), []
    for k, _ in pairs:
        if k in seen:
            dups.append(k)
        seen.add(k)
    out = _DupDict(d)
    out.dups = tuple(dups)
    return out


def _key_path(where: str, key) -> str:
    if isinstance(key, str) and NAME_RE.match(key):
        return f"{where}.{key}"
    return f"{where}[{json.dumps(key)}]"


def _walk(node, where: str, path):
    """Report duplicate keys and non-finite numbers anywhere in the document."""
    if isinstance(node, dict):
        if isinstance(node, _DupDict):
            raise FisError(path, where, f"duplicate key {node.dups[0]!r} in a JSON object")
        for k, v in node.items():
            _walk(v, _key_path(where, k), path)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _walk(v, f"{where}[{i}]", path)
    elif isinstance(node, float) and not math.isfinite(node):
        raise FisError(path, where, f"{node!r} is not a finite number (JSON has no "
                                    f"NaN/Infinity)")


def parse_json_text(text: str, path=None):
    """Parse rule-file text (strict: duplicate keys and NaN/Infinity are errors)."""
    try:
        doc = json.loads(text, object_pairs_hook=_pairs)
    except json.JSONDecodeError as exc:
        raise FisError(path, "", f"invalid JSON at line {exc.lineno} column {exc.colno}: "
                                 f"{exc.msg}") from None
    except RecursionError:
        raise FisError(path, "", "invalid JSON: nesting too deep") from None
    try:
        _walk(doc, "$", path)
    except RecursionError:
        raise FisError(path, "", "invalid JSON: nesting too deep") from None
    return doc


# ---------------------------------------------------------------------- validation
@lru_cache(maxsize=1)
def schema() -> dict:
    """The JSON Schema of format ``fuzzynav-fis`` version 1 (shipped with the package)."""
    text = resources.files("fuzzynav.fuzzy").joinpath("schema.json").read_text("utf-8")
    return json.loads(text)


@lru_cache(maxsize=1)
def _validator():
    import jsonschema

    cls = jsonschema.validators.validator_for(schema())
    return cls(schema())


def _check_header(doc, path):
    if not isinstance(doc, dict):
        raise FisError(path, "$", f"a rule file is a JSON object, got {type(doc).__name__}")
    fmt = doc.get("format")
    if fmt != FORMAT:
        raise FisError(path, "$.format", f"expected format {FORMAT!r}, got {fmt!r}")
    version = doc.get("version")
    if isinstance(version, bool) or version != VERSION:
        raise FisError(path, "$.version", f"unsupported version {version!r}; this fuzzynav "
                                          f"reads {FORMAT} version {VERSION}")


def schema_message(error) -> str:
    """A jsonschema error's message with the offending value quoted briefly.

    jsonschema quotes the whole value (``[...] is too long``): for a file of 140 000 rules
    that is a message of megabytes.  The JSON path says where the value is.
    """
    msg = error.message
    full = repr(error.instance)
    if len(full) > MAX_QUOTE and full in msg:
        msg = msg.replace(full, brief(error.instance))
    if len(msg) > 3 * MAX_QUOTE:  # a long value quoted some other way (a safety net)
        msg = f"{msg[:3 * MAX_QUOTE]}... (message cut from {len(msg)} characters)"
    return msg


def _size_errors(doc, path):
    """Top-level arrays longer than the schema allows, refused before anything walks them
    (the schema would first check each of, say, 140 000 rules: a minute)."""
    for key, spec in schema().get("properties", {}).items():
        value, limit = doc.get(key), spec.get("maxItems")
        if isinstance(value, list) and limit is not None and len(value) > limit:
            raise FisError(path, f"$.{key}", f"{len(value)} items; at most {limit} allowed")


def _schema_errors(doc, path):
    import jsonschema

    error = jsonschema.exceptions.best_match(_validator().iter_errors(doc))
    if error is not None:
        raise FisError(path, error.json_path, schema_message(error))


def validate_document(doc, path=None) -> None:
    """Check the header and the JSON Schema of a parsed document (not the semantics)."""
    _check_header(doc, path)
    _size_errors(doc, path)
    _walk(doc, "$", path)
    _schema_errors(doc, path)


# ------------------------------------------------------------------- dict <-> system
def _term(d) -> Term:
    return Term(d["name"], d["mf"], tuple(d["params"]))


def _variable(d) -> Variable:
    terms = []
    for k, t in enumerate(d["terms"]):
        with located(f"terms[{k}]"):
            terms.append(_term(t))
    return Variable(d["name"], tuple(d["range"]), tuple(terms), d.get("default"))


def _rule(d) -> Rule:
    antecedents = []
    for var, cond in d["if"].items():
        if isinstance(cond, dict):
            antecedents.append(Antecedent(var, cond["not"], True))
        else:
            antecedents.append(Antecedent(var, cond))
    return Rule(tuple(antecedents), tuple(d["then"].items()), d.get("weight", 1.0),
                d.get("connective", "and"))


def _canonical_order(fis_inputs, rule: Rule) -> Rule:
    order = {v.name: i for i, v in enumerate(fis_inputs)}
    ants = sorted(rule.antecedents, key=lambda a: order.get(a.variable, len(order)))
    return Rule(tuple(ants), rule.consequents, rule.weight, rule.connective)


def from_dict(doc, path=None) -> FuzzySystem:
    """Build a :class:`FuzzySystem` from a parsed ``fuzzynav-fis`` document.

    Parameters
    ----------
    doc : dict
        The document.
    path : str or os.PathLike, optional
        File it came from (named in error messages).
    """
    validate_document(doc, path)
    with located("$", path):
        ops = doc["operators"]
        operators = Operators(ops.get("and"), ops.get("or"), ops.get("implication"),
                              ops.get("aggregation"), ops.get("defuzzifier"))
        io_vars = {}
        for key in ("inputs", "outputs"):
            io_vars[key] = []
            for i, v in enumerate(doc[key]):
                with located(f"{key}[{i}]"):
                    io_vars[key].append(_variable(v))
        rules = []
        for r, d in enumerate(doc["rules"]):
            with located(f"rules[{r}]"):
                rules.append(_rule(d))
        rules = [_canonical_order(io_vars["inputs"], r) for r in rules]
        return FuzzySystem(doc["name"], doc["type"], operators, tuple(io_vars["inputs"]),
                           tuple(io_vars["outputs"]), tuple(rules),
                           *(doc.get(k) for k in OPTIONAL_OBJECTS))


# ---------------------------------------------------------------------- load / save
def _plain(obj):
    # numpy arrays and scalars in an in-memory document become plain JSON values
    tolist = getattr(obj, "tolist", None)
    if tolist is None:
        raise TypeError(f"{type(obj).__name__} is not JSON serialisable")
    return tolist()


def load_fis(source) -> FuzzySystem:
    """Load a fuzzy system from a rule file (``.json``; ``.fis`` = MATLAB) or a dict.

    Parameters
    ----------
    source : str, os.PathLike, Mapping or FuzzySystem
        Path of the file, or an already parsed document.

    Returns
    -------
    FuzzySystem

    Raises
    ------
    fuzzynav.fuzzy.FisError
        One line naming the file, the JSON path and what is wrong.
    """
    if isinstance(source, FuzzySystem):
        return source
    if isinstance(source, Mapping):
        try:
            text = json.dumps(dict(source), default=_plain)
        except (TypeError, ValueError) as exc:
            raise FisError(None, "$", f"not a JSON document: {exc}") from None
        return from_dict(parse_json_text(text), None)
    if not isinstance(source, (str, os.PathLike)):
        raise TypeError(f"load_fis takes a path or a dict, got {type(source).__name__}")
    if str(source).lower().endswith(".fis"):
        return read_matlab_fis(source)
    return from_dict(parse_json_text(read_text(source), source), source)


def dumps(doc, width: int = 96) -> str:
    """JSON text of a document: objects and arrays that fit in ``width`` stay on one line."""

    def emit(node, indent: int) -> str:
        flat = json.dumps(node, ensure_ascii=False, allow_nan=False)
        if not isinstance(node, (dict, list)) or len(flat) + indent <= width or not node:
            return flat
        pad = " " * (indent + 2)
        if isinstance(node, dict):
            items = [f"{pad}{json.dumps(k, ensure_ascii=False)}: {emit(v, indent + 2)}"
                     for k, v in node.items()]
            return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
        items = [pad + emit(v, indent + 2) for v in node]
        return "[\n" + ",\n".join(items) + "\n" + " " * indent + "]"

    return emit(doc, 0) + "\n"


def save_fis(fis: FuzzySystem, path) -> None:
    """Write ``fis`` as a ``fuzzynav-fis`` JSON file, atomically (``.fis``: MATLAB).

    Parameters
    ----------
    fis : FuzzySystem
    path : str or os.PathLike
        Destination; the extension ``.fis`` writes MATLAB format instead.
    """
    if str(path).lower().endswith(".fis"):
        write_matlab_fis(fis, path)
        return
    write_text_atomic(path, dumps(to_dict(fis)), what="rule file")


__all__ = ["load_fis", "save_fis", "from_dict", "to_dict", "schema", "validate_document",
           "parse_json_text", "dumps", "schema_message", "MAX_FILE_BYTES"]
