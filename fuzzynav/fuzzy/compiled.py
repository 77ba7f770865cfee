"""The compiled array form of a fuzzy system, for numba loops.

>>> cf = fis.compile()
>>> work = np.empty(cf.work_size); y = np.empty(cf.n_outputs)
>>> status = eval_compiled(cf.fparams, cf.iparams, x, y, work)

Two flat arrays carry the whole system (``fparams`` float64, ``iparams`` int64; layout
in :mod:`fuzzynav.fuzzy.compiled_layout`), so a filter can pass them through numba first-class
functions with fixed signatures.  Outputs with curved Mamdani terms (gauss, gbell...)
are refused: their exact path is adaptive quadrature in Python
(:mod:`fuzzynav.fuzzy.quadrature`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.fuzzy import compiled_layout as L
from fuzzynav.fuzzy._where import FisCompileError
from fuzzynav.fuzzy.kernels import (eval_compiled, eval_compiled_batch, eval_compiled_into,
                                    eval_compiled_parallel)
from fuzzynav.fuzzy.membership import SHAPES

__all__ = ["CompiledFIS", "compile_fis", "eval_compiled", "eval_compiled_batch",
           "eval_compiled_into", "eval_compiled_parallel"]


@dataclass(frozen=True, eq=False)
class CompiledFIS:
    """Array form of a :class:`~fuzzynav.fuzzy.system.FuzzySystem`.

    Attributes
    ----------
    fparams : numpy.ndarray
        float64 1-D: every float of the system (MF parameters, ranges, defaults, rule
        weights, quadrature tables).
    iparams : numpy.ndarray
        int64 1-D: header, counts, MF and operator codes, rule index tables.
    n_inputs, n_outputs : int
        Lengths of ``x`` and ``y`` for :func:`eval_compiled`.
    work_size : int
        Length of the ``work`` buffer :func:`eval_compiled` needs.
    input_names, output_names : tuple of str
        Order of ``x`` and ``y``.
    """

    fparams: np.ndarray
    iparams: np.ndarray
    n_inputs: int
    n_outputs: int
    work_size: int
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def evaluate(self, X: np.ndarray, parallel: bool = False):
        """Evaluate rows of ``X`` (n, n_inputs); return ``(Y, status)`` arrays."""
        X = np.ascontiguousarray(X, dtype=np.float64).reshape(-1, self.n_inputs)
        Y = np.empty((X.shape[0], self.n_outputs))
        status = np.empty(X.shape[0], dtype=np.int64)
        if parallel and X.shape[0] >= 4096:
            eval_compiled_parallel(self.fparams, self.iparams, X, Y, status, 64)
        else:
            eval_compiled_into(self.fparams, self.iparams, X, Y, status)
        return Y, status


class _Builder:
    """Appends tables to the int and float arrays and records their offsets."""

    def __init__(self):
        self.ints = [0] * L.HEADER
        self.floats: list[float] = []

    def table(self, slot: int, values) -> None:
        self.ints[slot] = len(self.ints)
        self.ints.extend(int(v) for v in values)

    def ftable(self, slot: int, values) -> None:
        self.ints[slot] = len(self.floats)
        self.floats.extend(float(v) for v in values)

    def fappend(self, values) -> int:
        off = len(self.floats)
        self.floats.extend(float(v) for v in values)
        return off


def _check_compilable(fis) -> None:
    for v in fis.outputs:
        for t in v.terms:
            if t.kind == "curved":
                raise FisCompileError(
                    f"output {v.name!r} term {t.name!r} is a curved '{t.mf}' set: the "
                    f"compiled kernel handles tri/trap/singleton Mamdani outputs and Sugeno "
                    f"outputs; evaluate it with mode='exact' (adaptive quadrature, Python) "
                    f"or mode='sampled'")


def _gl_tables(n_max: int) -> list[float]:
    # table n (1..n_max) at offset n (n - 1): node, weight pairs on [0, 1]
    out: list[float] = []
    for n in range(1, n_max + 1):
        x, w = np.polynomial.legendre.leggauss(n)
        for xi, wi in zip(0.5 * (x + 1.0), 0.5 * w):
            out += [xi, wi]
    return out


def _terms_tables(b: _Builder, variables):
    var_rows, term_rows, first = [], [], 0
    for v in variables:
        var_rows.append([first, len(v.terms)])
        for t in v.terms:
            term_rows.append([SHAPES[t.mf].code, b.fappend(t.params)])
        first += len(v.terms)
    return var_rows, term_rows, first


def compile_fis(fis) -> CompiledFIS:
    """Build the :class:`CompiledFIS` of ``fis`` (raises FisCompileError if impossible)."""
    _check_compilable(fis)
    b = _Builder()
    ops = fis.operators
    sugeno = fis.type == "sugeno"
    n_in, n_out, n_rules = len(fis.inputs), len(fis.outputs), len(fis.rules)
    agg = L.AGG_SUM if sugeno else L.CODES["aggregation"][ops.aggregation]
    imp = L.IMP_PROD if sugeno else L.CODES["implication"][ops.implication]
    merge_by_term = agg == L.AGG_MAX or (agg == L.AGG_SUM and imp == L.IMP_PROD)

    in_rows, in_terms, n_interm = _terms_tables(b, fis.inputs)
    out_first, out_terms, n_outterm = _terms_tables(b, fis.outputs)
    b.table(L.OFF_INVAR, [v for row in in_rows for v in row])
    b.table(L.OFF_INTERM, [v for row in in_terms for v in row])
    b.table(L.OFF_OUTTERM, [v for row in out_terms for v in row])

    in_index = {v.name: i for i, v in enumerate(fis.inputs)}
    in_term0 = [row[0] for row in in_rows]
    rules, antes = [], []
    for r in fis.rules:
        rules += [1 if r.connective == "or" else 0, len(antes) // 3, len(r.antecedents)]
        for a in r.antecedents:
            i = in_index[a.variable]
            antes += [i, in_term0[i] + fis.inputs[i].term_index(a.term), int(a.negated)]
    b.table(L.OFF_RULE, rules)
    b.table(L.OFF_ANTE, antes)

    ptr, cons, out_rows, pieces_max, cap_max = [0], [], [], 1, 2
    for o, v in enumerate(fis.outputs):
        for r, rule in enumerate(fis.rules):
            for out, term in rule.consequents:
                if out == v.name:
                    cons += [r, out_first[o][0] + v.term_index(term)]
        ptr.append(len(cons) // 2)
        kind = (L.OUT_SUGENO if sugeno else
                L.OUT_SINGLETON if v.terms[0].mf == "singleton" else L.OUT_PWL)
        n_pieces = len(v.terms) if merge_by_term else ptr[-1] - ptr[-2]
        n_pieces = max(n_pieces, 1)
        cap = 2 + (L.PIECE_VERTS - 2) * n_pieces
        if agg == L.AGG_MAX:
            segs = L.PIECE_VERTS - 1
            cap += segs * segs * n_pieces * (n_pieces - 1) // 2
        out_rows += [out_first[o][0], out_first[o][1], kind, cap]
        pieces_max, cap_max = max(pieces_max, n_pieces), max(cap_max, cap)
    b.table(L.OFF_OUTVAR, out_rows)
    b.table(L.OFF_OUTPTR, ptr)
    b.table(L.OFF_CONS, cons)

    b.ftable(L.F_INRANGE, [x for v in fis.inputs for x in v.range])
    b.ftable(L.F_OUTRANGE, [x for v in fis.outputs for x in v.range])
    b.ftable(L.F_DEFAULT, [v.default_value for v in fis.outputs])
    b.ftable(L.F_WEIGHT, [r.weight for r in fis.rules])
    ngl = (pieces_max + 3) // 2 if agg == L.AGG_PROBOR and not sugeno else 0
    b.ftable(L.F_GL, _gl_tables(ngl))

    h = b.ints
    h[L.TAG], h[L.N_IN], h[L.N_OUT], h[L.N_RULES] = L.TAG_VALUE, n_in, n_out, n_rules
    h[L.KIND] = L.SUGENO if sugeno else L.MAMDANI
    h[L.OP_AND] = L.CODES["and"][ops.and_]
    h[L.OP_OR] = L.CODES["or"][ops.or_]
    h[L.OP_IMP], h[L.OP_AGG] = imp, agg
    h[L.OP_DEFUZZ] = L.CODES["defuzzifier"][ops.defuzzifier]
    h[L.N_INTERM], h[L.N_OUTTERM], h[L.MERGE_BY_TERM] = n_interm, n_outterm, int(merge_by_term)
    h[L.NGL], h[L.PIECE_MAX], h[L.ENV_CAP] = ngl, pieces_max, cap_max
    sizes = [(L.W_X, n_in), (L.W_MU, n_interm), (L.W_FIRE, n_rules), (L.W_LEVEL, n_outterm),
             (L.W_PIECE, pieces_max * L.PIECE_STRIDE), (L.W_ENV, 6 * cap_max),
             (L.W_SCRATCH, max(48, 2 * pieces_max))]
    off = 0
    for slot, size in sizes:
        h[slot] = off
        off += size
    h[L.WORK_SIZE] = off
    return CompiledFIS(
        fparams=np.asarray(b.floats, dtype=np.float64),
        iparams=np.asarray(h, dtype=np.int64),
        n_inputs=n_in, n_outputs=n_out, work_size=off,
        input_names=fis.input_names, output_names=fis.output_names,
    )
