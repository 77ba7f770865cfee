"""The numba patches apply only on the checked numba releases; elsewhere numba is left as it
is and a run gives the same results through numba's own path."""
import numba as nb
import numba.experimental.function_type as function_type
import numpy as np
import pytest

from fuzzynav.filters import numba_patch_dispatch as patch
from fuzzynav.filters.runner import run_filter
from tests.filters.simple_data import CONFIG, run_inputs, trajectory


@pytest.mark.parametrize("version, checked", [
    ("0.58.1", False), ("0.59.0", False), ("0.67.1", False), ("0.68.0", True), ("0.68.1", True),
    ("0.69.0rc1", False), ("1.0.0", False)])
def test_the_patches_apply_only_on_the_checked_releases(version, checked):
    assert patch.numba_checked(version) is checked


def test_the_installed_numba_is_a_checked_one():
    # a new numba release fails here first: check the patches on it, then widen CHECKED_NUMBA
    assert patch.numba_checked(), (nb.__version__, patch.CHECKED_NUMBA)


@nb.njit("float64(float64)")
def _plus_two(x):
    return x + 2.0


@nb.njit
def _apply(fns, i, x):
    return fns[i](x)


def test_an_unchecked_numba_is_left_as_it_is(monkeypatch):
    monkeypatch.setattr(nb, "__version__", "0.99.0")
    before = dict(vars(_apply))
    assert patch.memoise_table_types(_apply) is _apply
    assert dict(vars(_apply)) == before  # no instance typeof_pyval
    patch.restore_kernel_addresses()
    try:
        patch.memoise_kernel_addresses()
        for name in ("_get_wrapper_address", "_get_jit_address"):
            assert not getattr(getattr(function_type, name), "memoised", False)
        assert _apply((_plus_two,), 0, 1.0) == 3.0
    finally:
        monkeypatch.undo()
        patch.memoise_kernel_addresses()  # as the package leaves it on a checked numba
    assert getattr(function_type._get_wrapper_address, "memoised", False)


def test_a_run_without_the_patches_gives_the_same_bits():
    """The filter on numba's own lookups and typing (as on an unchecked release) against the
    patched path: the same compiled loop, so the same bits."""
    from fuzzynav.filters import loop

    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, 7)
    patched = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    dispatchers = [d for d in vars(loop).values()
                   if isinstance(d, nb.core.dispatcher.Dispatcher) and "typeof_pyval" in vars(d)]
    assert dispatchers, "no loop dispatcher carries the memoised typing"
    saved = {d: vars(d)["typeof_pyval"] for d in dispatchers}
    patch.restore_kernel_addresses()
    try:
        for d in dispatchers:
            del d.typeof_pyval
        plain = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    finally:
        for d, f in saved.items():
            d.typeof_pyval = f
        patch.memoise_kernel_addresses()
    for a, b in ((patched.lla, plain.lla), (patched.sigma, plain.sigma),
                 (patched.events["gnss"].nis, plain.events["gnss"].nis)):
        np.testing.assert_array_equal(a, b)


class _Holder(tuple):
    """A tuple subclass standing for the loop's named tuples (the bank, its controller)."""


@nb.njit
def _first_row(h):
    return h[0][0] + h[1][0](1.0)


@pytest.fixture
def typed(monkeypatch):
    """A dispatcher with the memoised typing whose numba answers are counted."""
    from numba.core.registry import CPUDispatcher

    d = CPUDispatcher(_first_row.py_func)
    calls = []
    plain = d.typeof_pyval
    monkeypatch.setattr(d, "typeof_pyval", lambda v: calls.append(v) or plain(v))
    patch.memoise_table_types(d)
    return d, plain, calls


def test_a_tuple_holding_kernels_is_typed_once_per_type(typed):
    d, plain, calls = typed
    a = (np.zeros(3), (_plus_two,), 1, 2.0)
    b = (np.ones(3), (_plus_two,), 7, 5.0)  # other values, the same types
    assert d.typeof_pyval(a) == plain(a)
    assert d.typeof_pyval(b) == plain(b) and len(calls) == 1
    assert d(b[:2]) == 1.0 + 3.0


@pytest.mark.parametrize("other", [
    (np.zeros(3, np.float32), (_plus_two,), 1, 2.0),                  # dtype
    (np.zeros((3, 1)), (_plus_two,), 1, 2.0),                          # dimensions
    (np.zeros((3, 3))[:, 0], (_plus_two,), 1, 2.0),                    # layout
    (np.zeros(3), (_plus_two,), 1 << 63, 2.0),                         # past int64
    (np.zeros(3), (_plus_two,), 1.0, 2.0),                             # int -> float
    _Holder((np.zeros(3), (_plus_two,), 1, 2.0)),                      # the tuple's class
])
def test_any_change_of_type_is_typed_afresh(typed, other):
    d, plain, calls = typed
    base = (np.zeros(3), (_plus_two,), 1, 2.0)
    d.typeof_pyval(base)
    assert d.typeof_pyval(other) == plain(other) and len(calls) == 2
    assert plain(other) != plain(base)


def test_a_read_only_array_is_typed_afresh(typed):
    d, plain, calls = typed
    ro = np.zeros(3)
    ro.flags.writeable = False
    d.typeof_pyval((np.zeros(3), (_plus_two,)))
    assert d.typeof_pyval((ro, (_plus_two,))) == plain((ro, (_plus_two,))) and len(calls) == 2


def test_a_value_of_unknown_type_goes_to_numba_every_time(typed):
    d, _, calls = typed
    val = (np.zeros(3), (_plus_two,), 1j)
    d.typeof_pyval(val)
    d.typeof_pyval(val)
    assert len(calls) == 2
