"""Kernels of one signature compiled on first use (fuzzynav.filters.numba_lazy), and kernel
tables holding only the kernels a run uses: the same numba type either way, so the filter
loop keeps one compiled (cached) version for every filter."""
from __future__ import annotations

import pickle

import numba
import numba as nb
import numpy as np
from numba import types

from fuzzynav.filters import adaptation, loop, measurements
from fuzzynav.filters.adaptation import ADAPT_SIG, none_kernel
from fuzzynav.filters.error_st import EM_PHI, EM_ST
from fuzzynav.filters.numba_lazy import OneSignatureDispatcher, njit_signature, table_of
from fuzzynav.filters.measurements import MEAS_SIG, unused_kernel
from fuzzynav.filters.runner import run_filter
from tests.filters.simple_data import CONFIG, run_inputs, trajectory

SIG = types.float64(types.float64[:], types.int64)

def _toy():
    @njit_signature(SIG, cache=False)
    def scaled_sum(a, k):
        return k * a.sum()

    return scaled_sum

def test_compiled_on_first_use_for_its_one_signature_only():
    k = _toy()
    assert isinstance(k, OneSignatureDispatcher) and not k.is_compiled and not k.overloads
    assert k(np.arange(4.0), 2) == 12.0  # a C array from Python: runs the A-layout code
    assert k.is_compiled and list(k.overloads) == [SIG.args]
    assert k(np.arange(8.0)[::2], 1) == 12.0  # a strided view: the same overload
    assert list(k.overloads) == [SIG.args]

def test_typed_as_a_first_class_function_before_any_call():
    a, b = _toy(), _toy()
    assert numba.typeof((a, b)) == types.UniTuple(types.FunctionType(SIG), 2)
    assert a.is_compiled and b.is_compiled  # typing the table compiled them, as @njit(sig)

def test_a_jitted_caller_compiles_it():
    k = _toy()

    @nb.njit
    def call(a):
        return k(a, 3)

    assert call(np.ones(2)) == 6.0 and list(k.overloads) == [SIG.args]

def test_pickled_and_back_keeps_the_signature():
    k = _toy()
    k2 = pickle.loads(pickle.dumps(k))
    assert k2 is k or k2.lazy_sig == SIG

def test_a_table_replaces_the_unused_kernels_by_the_stand_in():
    assert table_of("abc", None, "-") == ("a", "b", "c")
    assert table_of("abc", [2, -1], "-") == ("-", "-", "c")  # -1: no adapter, no slot

def test_tables_of_used_kernels_type_as_the_full_tables():
    """The loop's argument types: the same for any choice of used kernels (one cached loop),
    here with none used (nothing but the stand-ins compiled)."""
    meas, index = measurements.kernel_table(used=set())
    assert set(meas) == {unused_kernel} and len(meas) == len(index)
    assert numba.typeof(meas) == types.UniTuple(types.FunctionType(MEAS_SIG), len(index))
    adapt, index = adaptation.kernel_table(used=())
    assert set(adapt) == {none_kernel} and len(adapt) == len(index)
    assert numba.typeof(adapt) == types.UniTuple(types.FunctionType(ADAPT_SIG), len(index))
    full, _ = measurements.kernel_table()
    assert len(full) == len(meas) and unused_kernel not in full



def test_a_single_phi_model_filter_takes_the_plain_loop():
    assert loop.loop_for(1, EM_PHI, 0) is loop.PLAIN_LOOP
    for n_local, em, ctl in ((2, EM_PHI, 0), (1, EM_ST, 0), (1, EM_PHI, 1), (3, EM_ST, 1)):
        assert loop.loop_for(n_local, em, ctl) is loop.run_loop


def test_the_plain_loop_gives_the_full_loops_numbers(monkeypatch):
    """The plain copy is the full loop without branches this run never takes (both compiled
    by the suite anyway: single filters and banks).  They are two compiled functions, so
    their numbers are compared within 1e-12 relative (here they agree bit for bit; another
    CPU or LLVM may order an operation differently), not with ==."""
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, 5)
    plain = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    monkeypatch.setattr(loop, "loop_for", lambda *args: loop.run_loop)
    full = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    for name in ("lla", "vel_n", "sigma"):
        np.testing.assert_allclose(getattr(plain, name), getattr(full, name), rtol=1e-12,
                                   atol=0.0)
    np.testing.assert_allclose(plain.events["gnss"].nis, full.events["gnss"].nis, rtol=1e-12,
                               atol=1e-15)
