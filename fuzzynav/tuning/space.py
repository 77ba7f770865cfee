"""Search space: a trial's parameters -> a fuzzy system (define-by-run, conditional).

For each controller (a template rule file):

* partition count of each variable from the configured set (``{ctrl}.n.{var}``);
* strong triangular partitions whose peaks come from positive gaps normalised into the
  variable's range (``{ctrl}.gap.{var}.{n}.{k}``) — always sorted, never rejected; with
  ``free_triangles`` each term also gets its own left/right spread
  (``{ctrl}.spread.{var}.{n}.{k}.{l|r}``);
* one categorical consequent per antecedent cell (``{ctrl}.rule.{n1}x{n2}>{no}.{i}.{j}``:
  each structure has its own parameters, so a multivariate sampler models them jointly),
  optional weights (``{ctrl}.weight.{struct}.{i}.{j}``);
* a partition count of 1 on an input switches it off (one term true on its whole range, so
  the rule table does not depend on it): a study can select inputs;
* a controller with a ``parent`` (:mod:`fuzzynav.tuning.warm_start`) writes its tuned
  parent's constants into every candidate's ``binding.parent``;
* the DoM window (``{ctrl}.window``) and the ends of the first output's range
  (``{ctrl}.out_lo``, ``{ctrl}.out_hi``) where configured;
* a template with several outputs (``r_scale`` and ``q_scale`` of ``rq-scaling``) gets a
  partition and a consequent per cell for each: the first output's parameters are named as
  above, a further output ``o`` adds ``.{o}`` (``{ctrl}.rule.{struct}.{o}.{i}.{j}``) with
  ``struct`` counting that output's terms;
* with ``types = ["mamdani", "sugeno"]`` the trial chooses (``{ctrl}.type``): a Sugeno
  system is zero-order TSK, each output term the constant at its triangle's peak, the
  weighted average of the fired rules' constants (``wtaver``).

``tune = "rules"`` keeps the template's terms verbatim (a strong partition with evenly spread
peaks for another count or a tuned output range; no gap or spread parameters),
``"breakpoints"`` keeps the template's rules verbatim (term counts and names then fixed to
the template's; with ``rule_weights`` each rule gets a weight ``{ctrl}.weight.rule.{i}``).
Any object with Optuna's ``suggest_int / suggest_float / suggest_categorical`` works as the
trial (``optuna.trial.FixedTrial`` rebuilds a system from stored parameters).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.fuzzy import (Antecedent, FuzzySystem, Operators, Rule, Term, Variable,
                            load_fis, standard_labels, triangular_partition)

__all__ = ["check_against_template", "ControllerSpace", "build_all"]

_GAP = (0.05, 1.0)
_SPREAD = (0.3, 1.5)


def check_against_template(cc) -> FuzzySystem:
    """Load a controller's template and check that the configuration fits it.

    Returns the template.  Raises :class:`InputFileError` without a file for a setting of
    the controller that does not fit (``where`` is the key in the controller's table), or
    the template's own error if the rule file is broken.
    """
    tmpl = load_fis(cc.template)
    if tmpl.type != "mamdani":
        raise InputFileError(None, "template", f"{cc.template}: tuning starts from a Mamdani "
                             f"system (this one: {tmpl.type}; types = [...] may make it "
                             f"Sugeno)")
    names = set(tmpl.input_names) | set(tmpl.output_names)
    for var in cc.partitions:
        if var not in names:
            raise InputFileError(None, f"partitions.{var}", f"the template {cc.template} "
                                 f"has no variable {var!r} ({', '.join(sorted(names))})")
    if cc.tune == "breakpoints":
        for v in tmpl.inputs + tmpl.outputs:
            if cc.partitions.get(v.name, (len(v.terms),)) != (len(v.terms),):
                raise InputFileError(None, f"partitions.{v.name}", "tune = 'breakpoints' "
                                     "keeps the template's rule table, so the term count "
                                     f"stays the template's ({len(v.terms)})")
    for out in tmpl.output_names:
        if 1 in cc.partitions.get(out, ()):
            raise InputFileError(None, f"partitions.{out}", "an output needs at least 2 "
                                 "terms (a count of 1 switches an input off)")
    lo, hi = tmpl.outputs[0].range
    if cc.output_low is not None and cc.output_range is None and not cc.output_low[1] < hi:
        raise InputFileError(None, "output_low", f"must lie below the template's upper end "
                                                 f"{hi} (or set output_range)")
    if cc.output_range is not None and cc.output_low is None and not lo < cc.output_range[0]:
        raise InputFileError(None, "output_range", f"must lie above the template's lower "
                                                   f"end {lo} (or set output_low)")
    return tmpl


@dataclass(frozen=True)
class ControllerSpace:
    """The search space of one controller (see the module docstring)."""

    config: object          # ControllerConfig
    template: FuzzySystem
    binding: Binding        # the template's, parsed once; tuned systems keep it

    @classmethod
    def from_config(cls, cc) -> "ControllerSpace":
        """Load the template and check the configuration (and its binding) against it."""
        tmpl = check_against_template(cc)
        return cls(cc, tmpl, Binding.of(tmpl, cc.template))

    # -- building ---------------------------------------------------------------------------
    def _p(self, key):
        return f"{self.config.name}.{key}"

    def _count(self, trial, var):
        counts = self.config.partitions.get(var.name, (len(var.terms),))
        if len(counts) == 1:
            return counts[0]
        return trial.suggest_categorical(self._p(f"n.{var.name}"), list(counts))

    def _peaks(self, trial, var, n, lo, hi):
        gaps = [trial.suggest_float(self._p(f"gap.{var.name}.{n}.{k}"), *_GAP)
                for k in range(n - 1)]
        c = np.concatenate([[0.0], np.cumsum(gaps)])
        peaks = lo + (hi - lo) * c / c[-1]
        peaks[-1] = hi  # lo + (hi - lo) can round one ulp past either side of hi
        return peaks

    def _terms(self, trial, var, n, lo, hi, labels):
        if self.config.tune == "rules":
            # the template's own terms (any shape) where its count and range still hold
            if n == len(var.terms) and var.range == (lo, hi):
                return var.terms
            return triangular_partition(np.linspace(lo, hi, n), labels)
        peaks = self._peaks(trial, var, n, lo, hi)
        if not self.config.free_triangles:
            return triangular_partition(peaks, labels)
        d = np.diff(peaks)
        tris = []
        for k in range(n):
            left = d[k - 1] if k > 0 else d[0]
            right = d[k] if k < n - 1 else d[-1]
            sl = trial.suggest_float(self._p(f"spread.{var.name}.{n}.{k}.l"), *_SPREAD)
            sr = trial.suggest_float(self._p(f"spread.{var.name}.{n}.{k}.r"), *_SPREAD)
            tris.append((peaks[k] - sl * left, peaks[k], peaks[k] + sr * right))
        return triangular_partition(tris, labels, strong=False)

    def _variable(self, trial, var, is_output, first=True):
        n = self._count(trial, var)
        lo, hi = var.range
        if n == 1 and not is_output:  # input selection: one term true on the whole range
            w = hi - lo
            return Variable(var.name, (float(lo), float(hi)),
                            (Term("any", "trap", (lo - w, lo, hi, hi + w)),), None)
        if is_output and first and self.config.output_range is not None:
            hi = trial.suggest_float(self._p("out_hi"), *self.config.output_range)
        if is_output and first and self.config.output_low is not None:
            lo = trial.suggest_float(self._p("out_lo"), *self.config.output_low)
        keep_names = self.config.tune == "breakpoints" or n == len(var.terms)
        labels = [t.name for t in var.terms] if keep_names else \
            standard_labels(n, "magnitude" if is_output or lo >= 0.0 else "signed")
        terms = self._terms(trial, var, n, lo, hi, labels)
        default = min(max(var.default if var.default is not None else lo, lo), hi) \
            if is_output else None
        return Variable(var.name, (float(lo), float(hi)), tuple(terms), default)

    def _rules(self, trial, inputs, outputs):
        if self.config.tune == "breakpoints":
            return self._template_rules(trial)
        counts = [len(v.terms) for v in inputs]
        cells = "x".join(map(str, counts))
        rules = []
        for cell in itertools.product(*[range(c) for c in counts]):
            key = ".".join(map(str, cell))
            then = []
            for j, out in enumerate(outputs):
                no = len(out.terms)
                name = f"rule.{cells}>{no}" + (f".{out.name}" if j else "") + f".{key}"
                k = trial.suggest_categorical(self._p(name), list(range(no)))
                then.append((out.name, out.terms[k].name))
            weight = 1.0
            if self.config.rule_weights:
                struct = cells + f">{len(outputs[0].terms)}"
                weight = trial.suggest_float(self._p(f"weight.{struct}.{key}"), 0.0, 1.0)
            ants = tuple(Antecedent(v.name, v.terms[i].name) for v, i in zip(inputs, cell))
            rules.append(Rule(ants, tuple(then), weight))
        return tuple(rules)

    def _template_rules(self, trial):
        """The template's rules verbatim (term names and counts are kept in this mode)."""
        rules = self.template.rules
        if not self.config.rule_weights:
            return rules
        return tuple(replace(r, weight=trial.suggest_float(self._p(f"weight.rule.{i}"), 0.0, 1.0))
                     for i, r in enumerate(rules))

    def build(self, trial) -> FuzzySystem:
        """The fuzzy system of a trial."""
        t = self.template
        inputs = tuple(self._variable(trial, v, False) for v in t.inputs)
        outputs = tuple(self._variable(trial, v, True, k == 0) for k, v in enumerate(t.outputs))
        binding = self.binding
        if self.config.parent is not None:  # warm start: the tuned parent's constants
            binding = replace(binding, parent=self.config.parent[2])
        if self.config.window is not None:
            binding = replace(binding, window=trial.suggest_int(self._p("window"),
                                                                *self.config.window))
        rules = self._rules(trial, inputs, outputs)
        kind = self._type(trial)
        ops = t.operators
        if kind == "sugeno":
            outputs = tuple(_sugeno_output(v) for v in outputs)
            ops = Operators(ops.and_, ops.or_, None, None, "wtaver")
        return FuzzySystem(name=f"{t.name}-tuned", type=kind, operators=ops, inputs=inputs,
                           outputs=outputs, rules=rules, binding=binding.to_dict())

    def _type(self, trial) -> str:
        types = self.config.types
        return types[0] if len(types) == 1 else trial.suggest_categorical(self._p("type"),
                                                                          list(types))


def _peak(term: Term) -> float:
    """Where a Mamdani output term sits: its peak (tri, singleton), the middle of its
    core (trap), else the mean of its parameters."""
    p = term.params
    if term.mf == "tri":
        return float(p[1])
    if term.mf == "trap":
        return 0.5 * (p[1] + p[2])
    return float(np.mean(p))


def _sugeno_output(var: Variable) -> Variable:
    """A Mamdani output as a zero-order Sugeno one: each term the constant at its peak."""
    terms = tuple(Term(t.name, "constant", (_peak(t),)) for t in var.terms)
    return Variable(var.name, var.range, terms, var.default)


def build_all(spaces, trial) -> dict:
    """Controller name -> fuzzy system for a trial."""
    return {s.config.name: s.build(trial) for s in spaces}
