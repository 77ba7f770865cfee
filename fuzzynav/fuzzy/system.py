"""Immutable definitions of a fuzzy system: Term, Variable, Rule, Operators, FuzzySystem.

Every constructor validates its own fields and raises :class:`FisError` with a path
relative to itself; :func:`fuzzynav.fuzzy.io.from_dict` prefixes those paths with the
JSON path of the object and the file name.  Evaluation state never lives here: see
:mod:`fuzzynav.fuzzy.inference` and :mod:`fuzzynav.fuzzy.compiled`.
"""
from __future__ import annotations

import copy
import math
import re
from dataclasses import dataclass, field
from functools import cached_property

from fuzzynav.fuzzy._where import fail, unique
from fuzzynav.fuzzy.document import to_dict
from fuzzynav.fuzzy.membership import SHAPES, check_params
from fuzzynav.fuzzy.validation import check_system

__all__ = ["NAME_RE", "MAMDANI_OPERATORS", "SUGENO_OPERATORS", "Term", "Variable", "Antecedent",
           "Rule", "Operators", "FuzzySystem"]

NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")

#: allowed operator names, per system type
MAMDANI_OPERATORS = {
    "and": ("min", "prod"),
    "or": ("max", "probor"),
    "implication": ("min", "prod"),
    "aggregation": ("max", "sum", "probor"),
    "defuzzifier": ("centroid", "bisector", "mom", "som", "lom"),
}
SUGENO_OPERATORS = {
    "and": ("min", "prod"),
    "or": ("max", "probor"),
    "defuzzifier": ("wtaver", "wtsum"),
}


def _check_name(name, where: str, what: str = "name"):
    if not isinstance(name, str) or not NAME_RE.match(name):
        fail(where, f"{what} must be an identifier (letter or _, then letters, digits, _; "
                    f"at most 64 characters), got {name!r}")


@dataclass(frozen=True)
class Term:
    """A linguistic term: a name, a membership shape and its parameters.

    Parameters
    ----------
    name : str
        Identifier (``NS``, ``small``...).
    mf : str
        Shape name, see :mod:`fuzzynav.fuzzy.membership`.
    params : tuple of float
        Shape parameters in MATLAB order, in the variable's unit.
    """

    name: str
    mf: str
    params: tuple[float, ...]

    def __post_init__(self):
        _check_name(self.name, "name")
        if self.mf not in SHAPES:
            fail("mf", f"unknown membership function {self.mf!r}; known: "
                       f"{', '.join(SHAPES)}")
        try:
            params = tuple(float(p) for p in self.params)
        except (TypeError, ValueError):
            fail("params", f"parameters must be numbers, got {self.params!r}")
        object.__setattr__(self, "params", params)
        check_params(self.mf, params, None, "params")

    @property
    def kind(self) -> str:
        """``pwl``, ``curved``, ``singleton`` or ``sugeno``."""
        return SHAPES[self.mf].kind


@dataclass(frozen=True)
class Variable:
    """An input or output variable: name, range ``(lo, hi)``, terms, optional default.

    Parameters
    ----------
    name : str
        Identifier.
    range : tuple of float
        ``(lo, hi)`` with ``lo < hi``; inputs are clamped to it, Mamdani outputs are
        defuzzified over it.
    terms : tuple of Term
        At least one term, unique names.
    default : float or None
        Outputs only: value returned when no rule fires (``None``: range midpoint).
    """

    name: str
    range: tuple[float, float]
    terms: tuple[Term, ...]
    default: float | None = None

    def __post_init__(self):
        _check_name(self.name, "name")
        try:
            lo, hi = (float(v) for v in self.range)
        except (TypeError, ValueError):
            fail("range", f"range must be two numbers [lo, hi], got {self.range!r}")
        if not (math.isfinite(lo) and math.isfinite(hi)):
            fail("range", f"range must be finite, got {[lo, hi]}")
        if not lo < hi:
            fail("range", f"range needs lo < hi, got [{lo!r}, {hi!r}]")
        object.__setattr__(self, "range", (lo, hi))
        object.__setattr__(self, "terms", tuple(self.terms))
        if not self.terms:
            fail("terms", "a variable needs at least one term")
        unique([t.name for t in self.terms], "terms", "term")
        if self.default is not None:
            d = float(self.default)
            if not (math.isfinite(d) and lo <= d <= hi):
                fail("default", f"default must be a finite value inside the range "
                                f"[{lo!r}, {hi!r}], got {self.default!r}")
            object.__setattr__(self, "default", d)

    @property
    def default_value(self) -> float:
        """The value an output holds when no rule fires (default, else range midpoint)."""
        return self.default if self.default is not None else 0.5 * sum(self.range)

    def term_index(self, name: str) -> int:
        """Index of the term called ``name`` (``KeyError`` if absent)."""
        for i, t in enumerate(self.terms):
            if t.name == name:
                return i
        raise KeyError(name)


@dataclass(frozen=True)
class Antecedent:
    """One condition ``variable is [not] term`` of a rule."""

    variable: str
    term: str
    negated: bool = False


@dataclass(frozen=True)
class Rule:
    """``if <antecedents joined by connective> then <output is term>...`` with a weight.

    Parameters
    ----------
    antecedents : tuple of Antecedent
        At least one; an input not named is "don't care".
    consequents : tuple of (str, str)
        ``(output name, term name)`` pairs, at least one.
    weight : float
        In [0, 1]; multiplies the firing strength.
    connective : str
        ``"and"`` or ``"or"``.
    """

    antecedents: tuple[Antecedent, ...]
    consequents: tuple[tuple[str, str], ...]
    weight: float = 1.0
    connective: str = "and"

    def __post_init__(self):
        object.__setattr__(self, "antecedents", tuple(self.antecedents))
        object.__setattr__(self, "consequents", tuple(tuple(c) for c in self.consequents))
        if not self.antecedents:
            fail("if", "a rule needs at least one condition")
        if not self.consequents:
            fail("then", "a rule needs at least one consequent")
        w = self.weight
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not 0.0 <= w <= 1.0:
            fail("weight", f"weight must be a number in [0, 1], got {w!r}")
        object.__setattr__(self, "weight", float(w))
        if self.connective not in ("and", "or"):
            fail("connective", f"connective must be 'and' or 'or', got {self.connective!r}")


@dataclass(frozen=True)
class Operators:
    """Fuzzy operators (names as in MATLAB).

    ``implication`` and ``aggregation`` are ``None`` for Sugeno systems.
    """

    and_: str = "min"
    or_: str = "max"
    implication: str | None = "min"
    aggregation: str | None = "max"
    defuzzifier: str = "centroid"

    def as_dict(self) -> dict:
        """The ``operators`` object of a rule file."""
        d = {"and": self.and_, "or": self.or_, "implication": self.implication,
             "aggregation": self.aggregation, "defuzzifier": self.defuzzifier}
        return {k: v for k, v in d.items() if v is not None}

    def check(self, fis_type: str):
        """Validate against the allowed names of ``fis_type``."""
        allowed = MAMDANI_OPERATORS if fis_type == "mamdani" else SUGENO_OPERATORS
        have = self.as_dict()
        for key, names in allowed.items():
            if key not in have:
                fail(f"operators.{key}", f"missing operator '{key}' ({fis_type})")
            if have[key] not in names:
                fail(f"operators.{key}", f"{key} must be one of {', '.join(names)} "
                                         f"for a {fis_type} system, got {have[key]!r}")
        for key in have:
            if key not in allowed:
                fail(f"operators.{key}", f"operator '{key}' does not apply to a {fis_type} "
                                         f"system")


@dataclass(frozen=True)
class FuzzySystem:
    """A complete Mamdani or Sugeno fuzzy inference system (immutable).

    Build it with :func:`fuzzynav.fuzzy.load_fis` (from a file or a dict) or directly
    from :class:`Variable`, :class:`Rule` and :class:`Operators`.  ``binding``,
    ``provenance`` and ``expected`` are free JSON objects carried along unchanged
    (treat them as read-only).
    """

    name: str
    type: str
    operators: Operators
    inputs: tuple[Variable, ...]
    outputs: tuple[Variable, ...]
    rules: tuple[Rule, ...]
    binding: dict | None = field(default=None, hash=False)
    provenance: dict | None = field(default=None, hash=False)
    expected: dict | None = field(default=None, hash=False)

    def __post_init__(self):
        for key in ("inputs", "outputs", "rules"):
            object.__setattr__(self, key, tuple(getattr(self, key)))
        for key in ("binding", "provenance", "expected"):
            object.__setattr__(self, key, copy.deepcopy(getattr(self, key)))
        if not isinstance(self.name, str) or not self.name.strip():
            fail("name", f"name must be a non-empty string, got {self.name!r}")
        if self.type not in ("mamdani", "sugeno"):
            fail("type", f"type must be 'mamdani' or 'sugeno', got {self.type!r}")
        self.operators.check(self.type)
        check_system(self)

    # -- convenience --------------------------------------------------------------
    @property
    def input_names(self) -> tuple[str, ...]:
        """Input names, in order."""
        return tuple(v.name for v in self.inputs)

    @property
    def output_names(self) -> tuple[str, ...]:
        """Output names, in order."""
        return tuple(v.name for v in self.outputs)

    def output(self, name: str) -> Variable:
        """The output variable called ``name``."""
        for v in self.outputs:
            if v.name == name:
                return v
        raise KeyError(name)

    @cached_property
    def is_compilable(self) -> bool:
        """True when the numba kernel can evaluate this system exactly."""
        return all(t.kind != "curved" for v in self.outputs for t in v.terms)

    def to_dict(self) -> dict:
        """The system as a ``fuzzynav-fis`` version-1 document (lossless)."""
        return to_dict(self)

    def compile(self):
        """The array form evaluated by the numba kernels, see :mod:`.compiled`."""
        return self._compiled

    @cached_property
    def _compiled(self):
        from fuzzynav.fuzzy.compiled import compile_fis

        return compile_fis(self)

    def evaluate(self, inputs, *, mode: str = "exact", n_points: int = 101,
                 return_info: bool = False, engine: str = "auto"):
        """Evaluate the system on scalar or array inputs (broadcast).

        Parameters
        ----------
        inputs : mapping
            Input name -> scalar or array (in the input's unit); all inputs required.
        mode : {"exact", "sampled"}
            ``exact``: closed-form (piecewise-linear sets) or adaptive quadrature (curved
            sets). ``sampled``: MATLAB ``evalfis`` emulation on ``n_points`` output points.
        n_points : int
            Output grid size of the sampled mode (MATLAB's default 101).
        return_info : bool
            Also return an :class:`~fuzzynav.fuzzy.inference.EvalInfo` (clamp counts...).
        engine : {"auto", "compiled", "python"}
            Exact-mode implementation: the numba kernel (``auto`` when compilable) or the
            pure-Python reference path.

        Returns
        -------
        dict or (dict, EvalInfo)
            Output name -> float (all inputs scalar) or ndarray of the broadcast shape.
        """
        from fuzzynav.fuzzy.batch import evaluate  # lazy: keeps ``import fuzzynav.fuzzy`` light

        return evaluate(self, inputs, mode=mode, n_points=n_points,
                        return_info=return_info, engine=engine)

