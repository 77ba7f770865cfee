"""The per-run shortcuts of the study path give what the plain computations give.

Kernel tables typed once per tuple and their addresses looked up once per kernel and
signature (:mod:`fuzzynav.filters.numba_patch_dispatch`), output rows kept as
views of what the loop wrote (a bank of one's local outputs formed from its master's), and the truth at a result's epochs remembered per trajectory
(:func:`fuzzynav.metrics.errors_vs_trajectory`).
"""
import gc
from dataclasses import replace

import numba as nb
import numpy as np
import pytest

from fuzzynav import metrics
from fuzzynav.filters import numba_patch_dispatch as dispatch
from fuzzynav.filters.numba_patch_dispatch import memoise_table_types
from fuzzynav.filters.result import FilterResult
from fuzzynav.filters.runner import run_filter
from fuzzynav.nav import attitude, earth
from tests.filters.simple_data import CONFIG, run_inputs, trajectory


@nb.njit("float64(float64)")
def _plus_one(x):
    return x + 1.0


@nb.njit("float64(float64)")
def _twice(x):
    return 2.0 * x


@nb.njit
def _apply(fns, i, x):
    return fns[i](x)


def test_a_kernel_table_is_typed_once_and_a_new_one_afresh():
    typed = []
    plain = _apply.typeof_pyval
    _apply.typeof_pyval = lambda v: (typed.append(v), plain(v))[1]
    memoise_table_types(_apply)
    assert _apply((_plus_one, _twice), 1, 3.0) == 6.0
    assert _apply((_plus_one, _twice), 0, 3.0) == 4.0  # a new tuple of the same kernels
    assert sum(type(v) is tuple for v in typed) == 1
    assert _apply((_twice, _plus_one), 1, 3.0) == 4.0  # other kernels at index 1
    assert sum(type(v) is tuple for v in typed) == 2


@nb.njit("float64(float64)")
def _minus_one(x):
    return x - 1.0


@nb.njit
def _halve(x):
    return 0.5 * x


def test_kernel_addresses_are_looked_up_once_per_kernel_and_signature():
    asked = []
    address = dispatch._memoised_address(lambda f, sig: (asked.append(f), id(f) + len(sig))[1])
    sig_a, sig_b = tuple([1, 2]), tuple([1, 2])  # equal but distinct objects: the unboxer's are one object
    assert address(_plus_one, sig_a) == id(_plus_one) + 2
    assert address(_plus_one, sig_a) == id(_plus_one) + 2
    assert address(_twice, sig_a) == id(_twice) + 2
    assert asked == [_plus_one, _twice]
    address(_plus_one, sig_b)  # another signature object
    assert len(asked) == 3
    _halve(1.0)
    address(_halve, sig_a)
    _halve(1)  # a new overload: asked afresh
    address(_halve, sig_a)
    assert asked[-2:] == [_halve, _halve] and len(asked) == 5
    text = "not a dispatcher"
    assert address(text, sig_a) == id(text) + 2
    assert len(asked) == 6  # anything else goes straight through


def test_memoised_addresses_still_call_the_right_kernels():
    dispatch.memoise_kernel_addresses()
    dispatch.memoise_kernel_addresses()  # idempotent: one memo layer
    for _ in range(3):  # the second and third calls come from the memo
        assert _apply((_minus_one, _twice), 0, 3.0) == 2.0
        assert _apply((_twice, _minus_one), 0, 3.0) == 6.0
        assert _apply((_twice, _minus_one), 1, 3.0) == 2.0


@pytest.fixture(scope="module")
def run():
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, 5)
    return tr, run_filter(imu, {"gnss": gnss}, init, CONFIG)


def _expected_errors(res, tr):
    """The errors computed directly (earth.delta_lla_to_enu, attitude.euler_error)."""
    k = np.searchsorted(tr.time_s, res.time_s - 1e-9)
    d = res.lla - tr.lla[k]
    pos = earth.delta_lla_to_enu(d[:, 0], d[:, 1], d[:, 2], tr.lla[k, 0], tr.lla[k, 2])
    return pos, res.vel_n - tr.vel_n[k], attitude.euler_error(res.att, tr.att[k])


def _check(res, tr):
    err = metrics.errors_vs_trajectory(res, tr)
    # the same floating-point operations in the same order: equal to the last bit (rtol 0)
    for got, want in zip((err.pos_m, err.vel_mps, err.att_rad), _expected_errors(res, tr)):
        np.testing.assert_allclose(got, want, rtol=0.0, atol=0.0)


def test_output_rows_are_all_written(run):
    tr, res = run
    n = int(round((tr.time_s[-1] - tr.time_s[0]) * CONFIG.out_rate_hz)) + 1
    assert res.time_s.shape == (n,) and np.all(np.diff(res.time_s) > 0)
    for arr in (res.lla, res.vel_n, res.q_bn, res.sigma, res.locals.x, res.locals.sigma):
        assert arr.shape[0] == n and np.isfinite(arr).all()


def test_a_bank_of_one_reports_its_master_as_its_local(run):
    """The loop records only the master of a bank of one; its local outputs are formed from
    it: the last sigma row against the final covariance (kept apart from the outputs)."""
    _, res = run
    loc = res.locals
    n = res.sigma.shape[1]
    assert loc.x.shape == loc.sigma.shape == (res.time_s.size, 1, n)
    assert np.all(loc.x == 0.0) and np.all(loc.beta == 1.0)
    np.testing.assert_array_equal(loc.sigma[:, 0], res.sigma)
    np.testing.assert_allclose(res.sigma[-1], np.sqrt(np.diag(loc.P_end[0])), rtol=1e-15)


def test_the_skipped_call_of_the_plain_ekf_is_a_policy_of_ones():
    """The loop does not call the plain EKF's policy (``loop.NO_ADAPTER``); a policy that
    returns the same ones, called, gives the same run (the calls multiply by exactly one, so
    the runs agree to the last bit here; 1e-12 allows for another compiler's scheduling)."""
    from fuzzynav.filters import loop
    from fuzzynav.filters.adaptation.classical import ConstantScale
    from fuzzynav.filters.sensor_tables import adapter_ids, pack_sensors

    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, 6)
    tables = pack_sensors({"gnss": gnss}, {}, {}, None)
    assert adapter_ids(tables.bounds).tolist() == [loop.NO_ADAPTER]
    plain = run_filter(imu, {"gnss": gnss}, init, CONFIG)
    called = run_filter(imu, {"gnss": gnss}, init, CONFIG, {"gnss": ConstantScale()})
    for a, b in ((plain.lla, called.lla), (plain.sigma, called.sigma),
                 (plain.events["gnss"].nis, called.events["gnss"].nis)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=0.0)


def test_errors_against_the_remembered_truth_equal_the_direct_ones(run):
    tr, res = run
    _check(res, tr)
    _check(res, tr)  # the second time from the memo
    assert tr in metrics._TRUTH_AT
    moved = replace(res, lla=res.lla + 1e-7, vel_n=res.vel_n * 1.5)  # another run, same epochs
    _check(moved, tr)
    half = replace(res, time_s=res.time_s[::2], lla=res.lla[::2], vel_n=res.vel_n[::2],
                   q_bn=res.q_bn[::2])  # other epochs: not the remembered ones
    _check(half, tr)
    _check(res, tr)


def test_the_memo_lets_its_trajectory_go():
    tr = trajectory(1)
    key = id(tr)
    res = _fake_result(tr)
    metrics.errors_vs_trajectory(res, tr)
    assert tr in metrics._TRUTH_AT
    del tr, res
    gc.collect()
    assert key not in metrics._TRUTH_AT._entries


def _fake_result(tr):
    """A 'result' at the truth's 1-Hz epochs with the truth's own state."""
    k = np.arange(0, tr.time_s.size, 100)
    time_s, lla, vel_n, q_bn = tr.time_s[k], tr.lla[k], tr.vel_n[k], tr.q_bn[k]
    return FilterResult(time_s=time_s, lla=lla, vel_n=vel_n, q_bn=q_bn,
                        sensor_states=np.zeros((time_s.size, 0)),
                        sigma=np.zeros((time_s.size, 15)), state_labels=())


def test_memoised_P0_and_q_diag_are_fresh_copies_of_what_a_new_config_computes():
    from fuzzynav.filters.config import FilterConfig
    from fuzzynav.filters.error_model import ErrorModel

    cfg = FilterConfig(model=ErrorModel(gyro_tau_s=(np.inf, 300.0)), gyro_sigma_dph=(5.0, 2.0),
                       gyro_rw_dph_psh=(0.0, 0.0))
    P0, q = cfg.P0(), cfg.q_diag()
    P0[0, 0], q[0] = -1.0, -1.0  # a caller changing its copy changes nothing for the next
    again = replace(cfg)  # a new instance assembles its arrays afresh
    np.testing.assert_array_equal(cfg.P0(), again.P0())  # same path, same inputs: exact
    np.testing.assert_array_equal(cfg.q_diag(), again.q_diag())
    # init_att_sigma_deg[0] = 0.1 deg, converted here by another path: to rounding
    assert cfg.P0()[0, 0] == pytest.approx((0.1 * np.pi / 180.0) ** 2, rel=1e-14)
    # Gauss-Markov gyro block 2: q = 2 sigma^2 / tau, sigma = 2 deg/h in rad/s
    sig = 2.0 * np.pi / 180.0 / 3600.0
    assert cfg.q_diag()[cfg.model.layout.start("gyro_bias:1")] == pytest.approx(
        2.0 * sig * sig / 300.0, rel=1e-12)
    assert cfg.P0().flags.writeable and cfg.q_diag().flags.writeable


def test_memoised_layout_and_block_arrays_leave_the_model_equal_and_the_arrays_fresh():
    from fuzzynav.filters.error_model import MODEL_15, ErrorModel

    model = ErrorModel(gyro_tau_s=(np.inf, 100.0))
    assert model.layout is model.layout and model.n_states == 18
    start, kind, inv_tau = model.block_arrays()
    inv_tau[:] = -1.0  # the loop is typed for writeable arrays: each call hands out copies
    assert model.block_arrays()[2].tolist() == [0.0, 0.01, 0.0]
    assert all(a.flags.writeable for a in model.block_arrays())
    MODEL_15.layout  # a cached layout is not a field: equality and hashing are unchanged
    assert MODEL_15 == ErrorModel() and hash(MODEL_15) == hash(ErrorModel())


def test_quat_to_euler_equals_the_angles_of_the_full_dcm():
    q = attitude.quat_normalize(np.random.default_rng(5).normal(size=(2000, 4)))
    # the same expressions on the same inputs: equal to rounding (0 in practice; the bound
    # allows a compiler reassociating a product)
    want = attitude.dcm_to_euler(attitude.quat_to_dcm(q))
    np.testing.assert_allclose(attitude.quat_to_euler(q), want, rtol=0, atol=1e-15)
    np.testing.assert_allclose(attitude.quat_to_euler(q[7]), want[7], rtol=0, atol=1e-15)
    # a known attitude: 30 deg pitch, 10 deg roll, heading 200 deg
    att = np.deg2rad([30.0, 10.0, 200.0])
    np.testing.assert_allclose(attitude.quat_to_euler(attitude.euler_to_quat(att)), att,
                               atol=1e-12)


def test_a_remembered_initial_state_is_the_draw_itself_in_fresh_arrays():
    from types import SimpleNamespace

    from fuzzynav import experiment, simsource
    from fuzzynav.filters.config import FilterConfig

    tr = trajectory()
    log = SimpleNamespace(seed=3, truth=tr)
    setup = SimpleNamespace(config=FilterConfig())
    first = experiment.perturbed_initial_state(log, setup)
    sig = np.sqrt(np.diag(FilterConfig().P0())[:9])
    drawn = simsource._draw_initial_state(3, tr, sig)
    for got in (first, experiment.perturbed_initial_state(log, setup)):
        # the same draw on the same inputs: exact
        for name in ("lla", "vel_n", "q_bn"):
            np.testing.assert_array_equal(getattr(got, name), getattr(drawn, name))
    first.lla[0] += 1.0  # a caller's change stays in its copy
    np.testing.assert_array_equal(experiment.perturbed_initial_state(log, setup).lla, drawn.lla)
    # another seed, or other sigmas, is another draw (velocity error ~0.1 m/s)
    other = experiment.perturbed_initial_state(SimpleNamespace(seed=4, truth=tr), setup)
    assert np.abs(other.vel_n - drawn.vel_n).max() > 1e-6
    wide = SimpleNamespace(config=FilterConfig(init_vel_sigma_mps=1.0))
    assert np.abs(experiment.perturbed_initial_state(log, wide).vel_n - drawn.vel_n).max() \
        > 1e-6
    # the draw: the truth plus errors of about the initial sigmas
    assert np.abs(drawn.vel_n - tr.vel_n[0]).max() < 5 * 0.1


def test_loop_kernels_divide_without_a_zero_test_and_a_zero_divisor_gives_inf():
    """Every kernel of the filter loop and the navigation maths is compiled with numba's
    numpy error model: a division is one instruction, with no test for a zero divisor and
    no ZeroDivisionError (a zero gives inf or NaN, which the loop's covariance check turns
    into a stopped run).  A kernel added without it would silently be slower."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import fuzzynav.filters
    import fuzzynav.nav
    from fuzzynav.nav import strapdown

    missing = []
    for pkg in (fuzzynav.filters, fuzzynav.nav):
        for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
            mod = importlib.import_module(info.name)
            for name, obj in vars(mod).items():
                own = isinstance(obj, CPUDispatcher) and obj.__module__ == mod.__name__
                if own and obj.targetoptions.get("error_model") != "numpy":
                    missing.append(f"{mod.__name__}.{name}")
    assert not missing, missing
    assert strapdown.inv_norm(0.0) == np.inf  # 1 / sqrt(0): inf, not an exception
