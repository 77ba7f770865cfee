"""The compiled numba kernel: agreement with the Python exact path, contract, flags."""
import numba
import numpy as np
import pytest

from fuzzynav.fuzzy import FisCompileError, load_fis
from fuzzynav.fuzzy.compiled import (CompiledFIS, eval_compiled, eval_compiled_batch,
                                     eval_compiled_into)
from tests.floats import assert_same_up_to_rounding, sum_order_rtol
from tests.fuzzy.systems import GPS, free_terms, mamdani_doc, random_mamdani, random_rules

OPS = [{"and": a, "or": o, "implication": i, "aggregation": g, "defuzzifier": d}
       for a, o in (("min", "max"), ("prod", "probor"))
       for i in ("min", "prod") for g in ("max", "sum", "probor")
       for d in ("centroid", "bisector", "mom", "som", "lom")]


def sugeno_doc(rng, n_inputs, kind):
    base = random_mamdani(rng, n_inputs=n_inputs, n_terms=3, n_out_terms=3,
                          negate_prob=0.2, or_prob=0.2, weight_prob=0.4)
    terms = [{"name": f"T{j}", "mf": kind,
              "params": [float(rng.uniform(-1, 1))] if kind == "constant"
              else [float(v) for v in rng.uniform(-1, 1, n_inputs + 1)]} for j in range(3)]
    base.update(type="sugeno", operators={"and": "prod", "or": "probor",
                                          "defuzzifier": "wtaver" if kind == "linear" else "wtsum"})
    base["outputs"][0]["terms"] = terms
    return base


def singleton_doc(rng, defuzz):
    base = random_mamdani(rng, n_inputs=2, n_terms=3, n_out_terms=3,
                          ops={"defuzzifier": defuzz, "aggregation": "probor"})
    base["outputs"][0]["terms"] = [{"name": f"T{j}", "mf": "singleton",
                                    "params": [float(v)]} for j, v in
                                   enumerate(rng.uniform(0, 1, 3))]
    return base


def _docs():
    rng = np.random.default_rng(11)
    for ops in OPS:
        yield random_mamdani(rng, n_inputs=2, n_terms=int(rng.integers(2, 5)),
                             n_out_terms=int(rng.integers(2, 6)), out_shapes=("tri", "trap"),
                             ops=ops, negate_prob=0.2, or_prob=0.2, weight_prob=0.3,
                             dont_care_prob=0.2)
    for kind in ("constant", "linear"):
        yield sugeno_doc(rng, 2, kind)
    for d in ("centroid", "mom", "som", "lom"):
        yield singleton_doc(rng, d)


@pytest.mark.parametrize("doc", list(_docs()), ids=lambda d: "-".join(d["operators"].values()))
def test_kernel_agrees_with_the_python_exact_path(doc):
    fis = load_fis(doc)
    rng = np.random.default_rng(5)
    X = rng.uniform(-1.3, 1.3, (40, len(fis.inputs)))
    X[0] = np.nan
    inputs = {n: X[:, i] for i, n in enumerate(fis.input_names)}
    got, info_c = fis.evaluate(inputs, engine="compiled", return_info=True)
    ref, info_p = fis.evaluate(inputs, engine="python", return_info=True)
    np.testing.assert_allclose(got["y"], ref["y"], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(info_c.status, info_p.status)


def test_compiled_form_contract():
    fis = load_fis(GPS)
    cf = fis.compile()
    assert isinstance(cf, CompiledFIS)
    assert cf.fparams.dtype == np.float64 and cf.fparams.ndim == 1
    assert cf.iparams.dtype == np.int64 and cf.iparams.ndim == 1
    assert (cf.n_inputs, cf.n_outputs) == (2, 1)
    assert cf.input_names == ("dom_pos", "dom_vel") and cf.output_names == ("alpha",)
    assert fis.compile() is cf  # cached on the immutable system
    with pytest.raises(Exception):
        cf.n_inputs = 3


@numba.njit
def _user_loop(fp, ip, X, n_out, work_size):
    # a caller's own numba loop: one work buffer, one output vector, many calls
    work = np.empty(work_size)
    y = np.empty(n_out)
    total = np.zeros(n_out)
    flags = 0
    for k in range(X.shape[0]):
        flags |= eval_compiled(fp, ip, X[k], y, work)
        total += y
    return total, flags


def test_eval_compiled_inside_a_numba_loop_and_on_views():
    fis = load_fis(GPS)
    cf = fis.compile()
    X = np.random.default_rng(0).uniform(-1.5, 1.5, (500, 2))
    total, flags = _user_loop(cf.fparams, cf.iparams, X, cf.n_outputs, cf.work_size)
    ref = fis.evaluate({"dom_pos": X[:, 0], "dom_vel": X[:, 1]}, engine="python")["alpha"]
    # the numba loop adds the 500 outputs in sequence, numpy's sum pairwise: two summation
    # orders of positive terms (and two engines per term, ~1e-15 apart)
    assert total[0] == pytest.approx(ref.sum(), rel=sum_order_rtol(len(X)), abs=0.0)
    assert flags == 1  # some inputs were clamped, every sample fired a rule
    # the filter embeds the arrays in larger ones and passes slices (views)
    fp = np.concatenate([[9.0, 9.0], cf.fparams])
    ip = np.concatenate([np.array([7, 7, 7], dtype=np.int64), cf.iparams])
    t2, _ = _user_loop(fp[2:], ip[3:], X, cf.n_outputs, cf.work_size)
    # exact on purpose: the same compiled loop on the same numbers, only at an offset in
    # memory; a wrong offset would read other parameters and give another value
    assert t2[0] == total[0]


def test_batch_counts_clamped_rows_and_flags_each_row():
    fis = load_fis(GPS)
    cf = fis.compile()
    X = np.array([[0.0, 0.0], [2.0, 0.0], [-3.0, -3.0], [np.nan, 0.0], [0.5, 0.5]])
    Y, n_clamped = eval_compiled_batch(cf.fparams, cf.iparams, X)
    assert n_clamped == 2
    status = np.empty(5, dtype=np.int64)
    Y2 = np.empty_like(Y)
    assert eval_compiled_into(cf.fparams, cf.iparams, X, Y2, status) == 2
    np.testing.assert_array_equal(status, [0, 1, 1, 4, 0])
    assert np.isnan(Y[3, 0]) and not np.isnan(Y[[0, 1, 2, 4], 0]).any()
    # two batch entry points over the per-row kernel: to rounding
    assert_same_up_to_rounding(Y[[0, 1, 2, 4]], Y2[[0, 1, 2, 4]])


@pytest.mark.parametrize("doc", list(_docs())[::5], ids=lambda d: "-".join(d["operators"].values()))
def test_a_batch_row_is_bit_identical_to_the_sample_alone(doc):
    # exact on purpose (docs/reliability.md promises it): both batch entry points run the same
    # scalar kernel, eval_compiled, once per row with no sum across rows, so a row cannot
    # depend on the others or on the batch length; a kernel that vectorised across rows or
    # summed in another order would break this
    cf = load_fis(doc).compile()
    X = np.random.default_rng(8).uniform(-1.3, 1.3, (64, cf.n_inputs))
    Y, _ = eval_compiled_batch(cf.fparams, cf.iparams, X)
    y, work = np.empty(cf.n_outputs), np.empty(cf.work_size)
    for k in range(len(X)):
        alone = np.empty((1, cf.n_outputs))
        eval_compiled_into(cf.fparams, cf.iparams, X[k:k + 1].copy(), alone,
                           np.empty(1, dtype=np.int64))
        eval_compiled(cf.fparams, cf.iparams, X[k].copy(), y, work)
        assert (Y[k] == alone[0]).all() and (Y[k] == y).all(), k


def test_no_rule_fired_flag_and_default():
    rng = np.random.default_rng(3)
    inputs = [{"name": "x", "range": [0.0, 1.0], "terms": [
        {"name": "A", "mf": "tri", "params": [0.0, 0.1, 0.2]}]}]
    out = free_terms(rng, 0.0, 1.0, 2)
    doc = mamdani_doc(inputs, out, random_rules(rng, inputs, out))
    doc["outputs"][0]["default"] = 0.3
    cf = load_fis(doc).compile()
    y = np.empty(1)
    work = np.empty(cf.work_size)
    assert eval_compiled(cf.fparams, cf.iparams, np.array([0.7]), y, work) == 2
    assert y[0] == 0.3


def test_curved_outputs_are_refused_with_a_clear_error():
    doc = random_mamdani(np.random.default_rng(2), n_inputs=1, n_terms=3, n_out_terms=2)
    doc["outputs"][0]["terms"][0] = {"name": "T0", "mf": "gauss", "params": [0.1, 0.5]}
    fis = load_fis(doc)
    with pytest.raises(FisCompileError, match="curved 'gauss'"):
        fis.compile()
    # evaluate still works (adaptive quadrature path)
    assert 0.0 <= fis.evaluate({"x0": 0.2})["y"] <= 1.0
