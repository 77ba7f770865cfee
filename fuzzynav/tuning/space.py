"""Search space: a trial's parameters -> a fuzzy system (define-by-run, conditional).

For each controller (a template rule file):

* partition count of each variable from the configured set (``{ctrl}.n.{var}``);
* strong triangular partitions whose peaks come from positive gaps normalised into the
  variable's range (``{ctrl}.gap.{var}.{n}.{k}``) — always sorted, never rejected; with
  ``free_triangles`` each term also gets its own left/right spread
  (``{ctrl}.spread.{var}.{n}.{k}.{l|r}``);
* one categorical consequent per antecedent cell (``{ctrl}.rule.{n1}x{n2}>{no}.{i}.{j}``:
  each structure has its own parameters, so a multivariate sampler models them jointly),
  optional weights (``{ctrl}.weight....``);
* the DoM window (``{ctrl}.window``) and the ends of the output range
  (``{ctrl}.out_lo``, ``{ctrl}.out_hi``) where configured.

``tune = "rules"`` keeps the template's breakpoints (evenly spread peaks for other counts),
``"breakpoints"`` keeps the template's rule table (counts then fixed to the template's).
Any object with Optuna's ``suggest_int / suggest_float / suggest_categorical`` works as the
trial (``optuna.trial.FixedTrial`` rebuilds a system from stored parameters).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.fuzzy import (Antecedent, FuzzySystem, Rule, Term, Variable, load_fis,
                            standard_labels, triangular_partition)

_GAP = (0.05, 1.0)
_SPREAD = (0.3, 1.5)


@dataclass(frozen=True)
class ControllerSpace:
    """The search space of one controller (see the module docstring)."""

    config: object          # ControllerConfig
    template: FuzzySystem

    @classmethod
    def from_config(cls, cc) -> "ControllerSpace":
        """Load the template and check the configuration against it."""
        tmpl = load_fis(cc.template)
        where = str(cc.template)
        if tmpl.type != "mamdani" or len(tmpl.outputs) != 1:
            raise InputFileError(where, "$", "tuning needs a Mamdani system with one output")
        names = set(tmpl.input_names) | set(tmpl.output_names)
        for var in cc.partitions:
            if var not in names:
                raise InputFileError(where, f"$.inputs/outputs",
                                     f"the study's partitions name {var!r}, which the template "
                                     f"does not have ({', '.join(sorted(names))})")
        if cc.tune == "breakpoints":
            for v in tmpl.inputs + tmpl.outputs:
                if cc.partitions.get(v.name, (len(v.terms),)) != (len(v.terms),):
                    raise InputFileError(where, f"$.{v.name}", "tune = 'breakpoints' keeps the "
                                         "template's rule table, so its term counts are fixed")
        return cls(cc, tmpl)

    # -- building ---------------------------------------------------------------------------
    def _p(self, key):
        return f"{self.config.name}.{key}"

    def _count(self, trial, var):
        counts = self.config.partitions.get(var.name, (len(var.terms),))
        if len(counts) == 1:
            return counts[0]
        return trial.suggest_categorical(self._p(f"n.{var.name}"), list(counts))

    def _peaks(self, trial, var, n, lo, hi):
        if self.config.tune == "rules":
            return self._template_peaks(var, n, lo, hi)
        gaps = [trial.suggest_float(self._p(f"gap.{var.name}.{n}.{k}"), *_GAP)
                for k in range(n - 1)]
        c = np.concatenate([[0.0], np.cumsum(gaps)])
        return lo + (hi - lo) * c / c[-1]

    def _template_peaks(self, var, n, lo, hi):
        peaks = [t.params[1] for t in var.terms] if all(t.mf == "tri" for t in var.terms) else []
        if len(peaks) == n and var.range == (lo, hi):
            return np.asarray(peaks, float)
        return np.linspace(lo, hi, n)

    def _terms(self, trial, var, n, lo, hi, labels):
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

    def _variable(self, trial, var, is_output):
        n = self._count(trial, var)
        lo, hi = var.range
        if is_output and self.config.output_range is not None:
            hi = trial.suggest_float(self._p("out_hi"), *self.config.output_range)
        if is_output and self.config.output_low is not None:
            lo = trial.suggest_float(self._p("out_lo"), *self.config.output_low)
        keep_names = self.config.tune == "breakpoints" or n == len(var.terms)
        labels = [t.name for t in var.terms] if keep_names else \
            standard_labels(n, "magnitude" if is_output else "signed")
        terms = self._terms(trial, var, n, lo, hi, labels)
        default = min(max(var.default if var.default is not None else lo, lo), hi) \
            if is_output else None
        return Variable(var.name, (float(lo), float(hi)), tuple(terms), default)

    def _rules(self, trial, inputs, output):
        counts = [len(v.terms) for v in inputs]
        no = len(output.terms)
        struct = "x".join(map(str, counts)) + f">{no}"
        table = self._template_table() if self.config.tune == "breakpoints" else None
        rules = []
        for cell in itertools.product(*[range(c) for c in counts]):
            key = ".".join(map(str, cell))
            if table is not None:
                if cell not in table:
                    continue
                out_term, weight = table[cell]
            else:
                k = trial.suggest_categorical(self._p(f"rule.{struct}.{key}"), list(range(no)))
                out_term, weight = output.terms[k].name, 1.0
            if self.config.rule_weights:
                weight = trial.suggest_float(self._p(f"weight.{struct}.{key}"), 0.0, 1.0)
            ants = tuple(Antecedent(v.name, v.terms[i].name) for v, i in zip(inputs, cell))
            rules.append(Rule(ants, ((output.name, out_term),), weight))
        return tuple(rules)

    def _template_table(self):
        """Template rules as {cell index tuple: (output term, weight)} (full AND cells)."""
        t = self.template
        out = {}
        for r in t.rules:
            if r.connective != "and" or any(a.negated for a in r.antecedents):
                continue
            idx = {a.variable: t.inputs[t.input_names.index(a.variable)].term_index(a.term)
                   for a in r.antecedents}
            if set(idx) != set(t.input_names):
                continue
            out[tuple(idx[n] for n in t.input_names)] = (r.consequents[0][1], r.weight)
        return out

    def build(self, trial) -> FuzzySystem:
        """The fuzzy system of a trial."""
        t = self.template
        inputs = tuple(self._variable(trial, v, False) for v in t.inputs)
        output = self._variable(trial, t.outputs[0], True)
        binding = dict(t.binding or {})
        if self.config.window is not None:
            binding["window"] = trial.suggest_int(self._p("window"), *self.config.window)
        return FuzzySystem(name=f"{t.name}-tuned", type=t.type, operators=t.operators,
                           inputs=inputs, outputs=(output,),
                           rules=self._rules(trial, inputs, output), binding=binding)


def build_all(spaces, trial) -> dict:
    """Controller name -> fuzzy system for a trial."""
    return {s.config.name: s.build(trial) for s in spaces}
