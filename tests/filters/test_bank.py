"""Filter banks (:mod:`fuzzynav.filters.bank`) against what theory says they must equal.

(a) reset mode, equal shares, fused after every update == the centralized filter;
(b) the bank of one == the single filter (the same code path: bit for bit);
(c) no-reset mode: a local == that filter run alone with its sensors (and its 1/beta-inflated
    noise), and the fused covariance is below every local's;
(d) bad bank descriptions raise one clear error.
"""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters.bank import BankSpec
from fuzzynav.filters.layout import LAYOUT_15
from fuzzynav.filters.named import FilterContext, get_filter
from fuzzynav.filters.runner import run_filter
from fuzzynav.nav import earth
from fuzzynav.sim.sensors import SensorData
from tests.filters.simple_data import CONFIG, gnss_fixes, run_inputs, trajectory

NHC_SIGMA = 0.05  # m/s
POS, VEL = LAYOUT_15.pos, LAYOUT_15.vel
#: a 0.1 deg heading prior: the locals' headings then stay within ~0.05 deg of the fused one,
#: where second-order terms are small (with 1 deg, |f| dpsi^2 t^2 / 2 reaches 0.15 sigma in
#: the first acceleration: a real second-order effect, not a bug)
LINEAR = CONFIG.with_(init_att_sigma_deg=(0.05, 0.05, 0.1))


def nhc(tr, rate_hz=10.0):
    """Zero lateral and vertical body velocity (the trajectory flies along its nose)."""
    t = tr.time_s[::int(round(tr.imu_rate_hz / rate_hz))]
    return SensorData("nhc", t, np.zeros((t.size, 2)), np.full((t.size, 2), NHC_SIGMA))


@pytest.fixture(scope="module")
def data():
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, seed=3)
    return tr, imu, {"gnss": gnss, "nhc": nhc(tr)}, init


def run(data, sensors=None, base=CONFIG, **config):
    _, imu, all_sensors, init = data
    return run_filter(imu, sensors or all_sensors, init, base.with_(**config))


def enu_between(lla, lla_ref):
    """ENU metres of ``lla`` about ``lla_ref``, row by row."""
    return np.array([earth.lla_to_enu(*a, *b) for a, b in zip(lla, lla_ref)])


def test_reset_mode_with_equal_shares_is_the_centralized_filter(data):
    # Carlson's equivalence (derived in fuzzynav.filters.bank): exact in exact arithmetic,
    # for the closed-loop filter too, since every update is fed back before the next one.
    # What is left is rounding in the information fusion (inverses of the 15x15 covariances
    # scaled to unit diagonal, conditioned ~1e6 here): ~1e-10 relative per fusion, damped by
    # the filter; 1e-6 of the filter's own sigma leaves two orders of magnitude to spare.
    central = run(data)
    fed = run(data, bank=BankSpec((("gnss",), ("nhc",)), (0.5, 0.5), "reset"))
    assert central.ok and fed.ok
    sig_pos = central.state_sigma("pos")
    assert np.all(np.abs(enu_between(fed.lla, central.lla)) <= 1e-6 * sig_pos)
    assert np.all(np.abs(fed.vel_n - central.vel_n) <= 1e-6 * central.state_sigma("vel"))
    np.testing.assert_allclose(fed.sigma, central.sigma, rtol=1e-6)
    # each local holds P_c / beta, i.e. sigma * sqrt(2), once the first fusion has happened
    k = fed.time_s >= 1.0
    np.testing.assert_allclose(fed.locals.sigma[k, 0], central.sigma[k] * np.sqrt(2), rtol=1e-6)
    # the test can fail: without the information share the same bank is another filter
    unshared = run(data, bank=BankSpec((("gnss",), ("nhc",)), (0.5, 0.5), "no-reset"))
    assert np.max(np.abs(enu_between(unshared.lla, central.lla)) / sig_pos) > 1e-3


def test_a_bank_of_one_is_the_single_filter_bit_for_bit(data):
    # the same code path (no fusion for one local, beta = 1 divides exactly): bit-identity
    # is the property under test here, so == is right
    single = run(data)
    for mode in ("reset", "no-reset"):
        one = run(data, bank=BankSpec((("gnss", "nhc"),), (1.0,), mode))
        for field in ("time_s", "lla", "vel_n", "q_bn", "sensor_states", "sigma"):
            assert np.array_equal(getattr(one, field), getattr(single, field)), (mode, field)
        assert np.array_equal(one.events["nhc"].nis, single.events["nhc"].nis, equal_nan=True)


def inflated(c, beta):
    """The configuration ``c`` with Carlson's P0 / beta and Q / beta."""
    s = 1.0 / np.sqrt(beta)
    return dict(init_att_sigma_deg=tuple(np.multiply(c.init_att_sigma_deg, s)),
                init_vel_sigma_mps=c.init_vel_sigma_mps * s,
                init_pos_sigma_m=c.init_pos_sigma_m * s,
                gyro_sigma_dph=tuple(np.multiply(c.gyro_sigma_dph, s)),
                accel_sigma_ug=tuple(np.multiply(c.accel_sigma_ug, s)),
                arw_dpsh=c.arw_dpsh * s, vrw_ug_psqrthz=c.vrw_ug_psqrthz * s)


@pytest.fixture(scope="module")
def two_receivers(data):
    tr = data[0]
    imu, gnss, init, _, _ = run_inputs(tr, 5, LINEAR)
    other = gnss_fixes(tr, np.random.default_rng(99))
    return tr, imu, {"gnss_a": gnss, "gnss_b": other}, init


def test_no_reset_locals_are_the_filters_alone(two_receivers):
    bank = BankSpec((("gnss_a",), ("gnss_b",)), (0.5, 0.5), "no-reset")
    fed = run(two_receivers, base=LINEAR, bank=bank)
    assert fed.ok
    for k, name in enumerate(("gnss_a", "gnss_b")):
        alone = run(two_receivers, {name: two_receivers[2][name]}, **inflated(LINEAR, 0.5))
        # the local's own estimate is the shared solution minus its error state; x is
        # recorded as of the last update, so compare at the GNSS epochs (whole seconds)
        at = np.isclose(fed.time_s, np.round(fed.time_s))
        x = fed.locals.x[at, k]
        own_pos = enu_between(alone.lla[at], fed.lla[at]) + x[:, POS]
        own_vel = alone.vel_n[at] - fed.vel_n[at] + x[:, VEL]
        sig = alone.sigma[at]
        # equal up to second-order terms (F and H taken at the shared solution, ~0.5 m and
        # ~0.05 m/s away from the local's own): measured <= 5e-3 sigma for the estimates and
        # 3e-3 relative for the sigmas; without the shift x_i -= x_g: ~800 sigma
        assert np.max(np.abs(own_pos) / sig[:, POS]) < 1e-2
        assert np.max(np.abs(own_vel) / sig[:, VEL]) < 1e-2
        np.testing.assert_allclose(fed.locals.sigma[at, k], sig, rtol=1e-2)
        # ...and they are not trivially equal: the fused solution is elsewhere
        assert np.median(np.abs(x[:, POS]) / sig[:, POS]) > 0.1


def test_fused_covariance_is_below_every_local(two_receivers):
    # the last GNSS fixes fall on the last IMU sample, so P_end and P_fused are of the last
    # fusion: P_g^-1 = sum P_i^-1 >= P_i^-1, i.e. P_i - P_g is positive semi-definite
    fed = run(two_receivers, base=LINEAR,
              bank=BankSpec((("gnss_a",), ("gnss_b",)), mode="no-reset"))
    loc = fed.locals
    info = sum(np.linalg.inv(P) for P in loc.P_end)
    np.testing.assert_allclose(loc.P_fused, np.linalg.inv(info), rtol=1e-6,
                               atol=1e-9 * np.sqrt(np.outer(np.diag(loc.P_fused),
                                                            np.diag(loc.P_fused))).max())
    for P in loc.P_end:
        d = 1.0 / np.sqrt(np.diag(P))  # compare on a scale where every state counts
        gap = np.linalg.eigvalsh(d[:, None] * (P - loc.P_fused) * d[None, :])
        assert gap.min() > -1e-9
    assert np.all(fed.sigma <= fed.locals.sigma[:, 0] * (1 + 1e-9))
    assert np.all(fed.sigma <= fed.locals.sigma[:, 1] * (1 + 1e-9))


@pytest.mark.parametrize("locals_, beta, where, what", [
    ((("gnss",), ("gnss", "nhc")), None, "bank.locals[1]", "already in local filter 0"),
    ((("gnss",), ("nhc",)), (0.5, 0.6), "bank.beta", "sum to 1"),
    ((("gnss",), ("nhc",)), (1.0,), "bank.beta", "one positive share per local"),
])
def test_bad_bank_descriptions_are_refused(locals_, beta, where, what):
    with pytest.raises(InputFileError) as err:
        BankSpec(locals_, beta)
    assert err.value.where == where and what in str(err.value)


def test_a_bank_must_name_the_runs_sensors(data):
    with pytest.raises(InputFileError, match=r"bank.locals\[1\]: unknown sensor 'dvl'"):
        run(data, bank=BankSpec((("gnss",), ("nhc", "dvl"))))
    with pytest.raises(InputFileError, match="sensor 'nhc' of the run is in no local"):
        run(data, bank=BankSpec((("gnss",),)))


def test_named_banks(data):
    _, imu, sensors, init = data
    ctx = FilterContext(sensors=sensors)
    fed = get_filter("federated").make(ctx).config.bank
    assert fed.locals == (("gnss",), ("nhc",)) and fed.mode == "no-reset"
    assert get_filter("federated-reset").make(ctx).config.bank.mode == "reset"
    central = get_filter("centralized").make(ctx).config
    assert central.bank.locals == (("gnss", "nhc"),) and central.bank.beta == (1.0,)


def test_a_fusion_period_lets_the_locals_run_between_fusions(data):
    central = run(data)
    fed = run(data, bank=BankSpec((("gnss",), ("nhc",)), mode="reset", fusion_period_s=1.0))
    assert fed.ok
    x = fed.locals.x
    # the 10-Hz constraint updates of local 1 are held between the 1-s fusions ...
    between = ~np.isclose(fed.time_s, np.round(fed.time_s)) & (fed.time_s > 2.0)
    assert np.all(np.abs(x[between, 1, VEL]).max(axis=1) > 0.0)
    # ... and local 0 (GNSS, once a second) restarts from the fused solution at every fusion
    at = np.isclose(fed.time_s, np.round(fed.time_s)) & (fed.time_s > 0.5)
    assert np.all(x[at, 0] == 0.0)  # set, not computed: exactly 0
    # another filter than the centralized one, but the same solution within its sigma
    assert np.all(np.abs(enu_between(fed.lla, central.lla)) < 3 * central.state_sigma("pos"))
