"""The fuzzy share controller of a filter bank (:mod:`fuzzynav.filters.bank_beta`).

(a) the share arithmetic: normalised weights with a floor;
(b) a controller whose output is constant is the bank with those fixed shares, bit for bit;
(c) a local whose sensor is disturbed gets a lower share;
(d) bad controllers and rule files give one clear error.
"""
import copy
import json
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.filters.bank import BankSpec
from fuzzynav.filters.bank_beta import floor_shares, push_innovation, stat_size, window_stat
from fuzzynav.filters.beta_controller import ShareController
from fuzzynav.filters.catalog import bind_systems
from fuzzynav.filters.runner import run_filter
from fuzzynav.fuzzy.io import from_dict, load_fis
from tests.filters.test_bank import data, nhc  # noqa: F401  (the module-scoped fixture)
from tests.filters.simple_data import CONFIG

RULES = Path(__file__).resolve().parents[2] / "rules" / "paper001_beta.json"


def beta_doc() -> dict:
    return json.loads(RULES.read_text())


def constant_doc() -> dict:
    """A controller whose every rule gives the same symmetric term: weight 1 for any input."""
    doc = beta_doc()
    doc["rules"] = [{"if": {"nis": t}, "then": {"w": "trust"}, "weight": 1.0}
                    for t in ("ok", "high", "huge")]
    return doc


@pytest.mark.parametrize("w, floor, expect", [
    ([1.0, 1.0, 1.0], 0.05, [1 / 3, 1 / 3, 1 / 3]),
    ([2.0, 1.0, 1.0], 0.05, [0.5, 0.25, 0.25]),
    # 0.01 / 2.01 < 0.1: fixed at the floor, the other two share 0.9 equally
    ([1.0, 1.0, 0.01], 0.1, [0.45, 0.45, 0.1]),
    # fixing one may push another under the floor: both fixed, the third takes the rest
    ([1.0, 0.12, 0.1], 0.1, [0.8, 0.1, 0.1]),
])
def test_shares_are_the_normalised_weights_with_a_floor(w, floor, expect):
    out = np.zeros(len(w))
    floor_shares(np.array(w), floor, out)
    np.testing.assert_allclose(out, expect, rtol=1e-12)
    assert abs(out.sum() - 1.0) < 1e-12


def test_window_statistics_are_the_window_means():
    st = np.zeros(stat_size(2))
    assert window_stat(st, 0) == 1.0 and window_stat(st, 1) == 1.0  # empty: consistent
    S = np.diag([4.0, 1.0])
    for nis, z in ((3.0, [2.0, 0.0]), (5.0, [0.0, 3.0]), (1.0, [1.0, 1.0])):
        push_innovation(st, nis, 2, np.array(z), S)
    # the window keeps the last two epochs: (nis 5, rr 9) and (nis 1, rr 2), 2 rows, tr S 5
    assert window_stat(st, 0) == pytest.approx((5.0 + 1.0) / 4)
    assert window_stat(st, 1) == pytest.approx((9.0 + 2.0) / 10)


def _bank(controller=None, beta=(0.5, 0.5), **kw):
    return BankSpec((("gnss",), ("nhc",)), beta, "no-reset", controller=controller, **kw)


def _run(data, bank, sensors=None):
    _, imu, all_sensors, init = data
    return run_filter(imu, sensors or all_sensors, init, CONFIG.with_(bank=bank))


def test_a_constant_controller_is_the_bank_with_fixed_shares(data):
    # weight 1 for both locals -> shares 1/2 each, the fixed shares: the same filter
    fixed = _run(data, _bank())
    ctl = _run(data, _bank(ShareController(from_dict(constant_doc()), "constant")))
    assert fixed.ok and ctl.ok
    np.testing.assert_array_equal(ctl.locals.beta, 0.5)
    np.testing.assert_allclose(ctl.lla, fixed.lla, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ctl.vel_n, fixed.vel_n, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ctl.sigma, fixed.sigma, rtol=1e-12)
    # ...and the shares it sets do act (the test can fail): started from 0.7 / 0.3, the same
    # controller moves them to 1/2 each at the first fusion, away from the fixed 0.7 / 0.3
    moved = _run(data, _bank(ShareController(from_dict(constant_doc()), "constant"), (0.7, 0.3)))
    np.testing.assert_array_equal(moved.locals.beta[-1], 0.5)
    other = _run(data, _bank(beta=(0.7, 0.3)))
    assert np.max(np.abs(moved.vel_n - other.vel_n)) > 1e-6


def test_a_local_whose_sensor_is_disturbed_gets_a_lower_share(data):
    tr, _, sensors, _ = data
    bad = copy.deepcopy(sensors["nhc"])
    zone = (bad.time_s >= 100.0) & (bad.time_s < 150.0)
    bad.z[zone, 0] += 1.0  # a 1-m/s lateral slip, 20 sigma of the non-holonomic constraint
    res = _run(data, _bank(ShareController(load_fis(RULES), str(RULES))), {**sensors, "nhc": bad})
    assert res.ok
    beta, t = res.locals.beta, res.time_s
    onset = (t >= 100.0) & (t < 112.0)
    before = (t >= 40.0) & (t < 100.0)
    np.testing.assert_allclose(beta.sum(axis=1), 1.0, rtol=1e-12)
    # consistent before: near the equal shares; as the slip sets in, the NHC local's NIS
    # jumps and its share falls to the floor.  (It does not stay there: the local absorbs the
    # slip into its own velocity estimate within seconds, its innovations turn consistent
    # again and it wins its share back -- a controller of innovations sees a local's
    # disagreement with its own past, not with the other locals.)
    assert np.all(np.abs(beta[before, 1] - 0.5) < 0.1)
    assert np.median(beta[onset, 1]) < 0.1
    assert np.all(beta[:, 1] >= 0.05 - 1e-12)


def _error(doc, source="beta.json"):
    with pytest.raises(InputFileError) as e:
        ShareController(from_dict(doc), source)
    return str(e.value)


def test_bad_controllers_give_one_clear_error():
    doc = beta_doc()
    doc["binding"]["windw"] = 3
    assert "$.binding.windw" in _error(doc) and "unknown key" in _error(doc)
    doc = beta_doc()
    doc["binding"]["inputs"]["nis"]["statistic"] = "dom"
    assert "$.binding.inputs.nis.statistic" in _error(doc)
    doc = beta_doc()
    doc["binding"]["inputs"]["nis"]["channel"] = "heading"
    assert "$.binding.inputs.nis.channel" in _error(doc)
    doc = beta_doc()
    doc["binding"]["sensor"] = "mag"
    assert "$.binding.sensor" in _error(doc)
    doc = beta_doc()
    doc["binding"]["outputs"] = {"w": "r_scale"}
    assert "$.binding.outputs.w" in _error(doc)
    ctl = ShareController(from_dict(beta_doc()), "beta.json")
    with pytest.raises(InputFileError, match="bank.controller.floor"):
        BankSpec((("a",), ("b",)), None, "no-reset", controller=ShareController(
            from_dict(beta_doc()), "beta.json", floor=0.5))
    with pytest.raises(InputFileError, match="beta_floor"):
        ShareController(from_dict(beta_doc()), "beta.json", floor="0.1")
    with pytest.raises(InputFileError, match="reset mode fused after every update"):
        BankSpec((("a",), ("b",)), None, "reset", controller=ctl)
    # a share controller is no per-sensor policy
    with pytest.raises(FuzzynavError, match="controls a filter bank"):
        bind_systems([(from_dict(beta_doc()), "beta.json")], {})


def test_a_share_change_rescales_the_local_noise_by_old_over_new():
    """``Q_i = Q / beta_i``: when the controller moves a share from ``beta_old`` to
    ``beta_new``, the local's noise density is multiplied by ``beta_old / beta_new`` -- a
    local whose share falls gets *more* process noise (less information), one whose share
    rises gets less.  The constant controller gives weight 1 to both locals: shares 1/2."""
    from fuzzynav.filters.bank_beta import update_shares

    ctl = ShareController(from_dict(constant_doc()), "constant").share_control(2)
    beta = np.array([0.7, 0.3])
    qd = np.array([[1.0, 2.0, 4.0], [1.0, 2.0, 4.0]])
    assert update_shares(ctl, beta, qd)
    np.testing.assert_allclose(beta, [0.5, 0.5], rtol=1e-12)
    # local 0 lost share (0.7 -> 0.5): Q / 0.5 > Q / 0.7, noise up by 0.7/0.5
    np.testing.assert_allclose(qd[0], np.array([1.0, 2.0, 4.0]) * 0.7 / 0.5, rtol=1e-12)
    np.testing.assert_allclose(qd[1], np.array([1.0, 2.0, 4.0]) * 0.3 / 0.5, rtol=1e-12)
    # the densities always equal Q / beta_i for the one shared Q = qd_i * beta_i
    np.testing.assert_allclose(qd[0] * beta[0], qd[1] * beta[1] * 0.7 / 0.3, rtol=1e-12)


def test_a_falling_share_widens_that_local_covariance(data):
    """The effect of the rule on a run: shares moved from 0.3 to 0.5 give local 1 less
    process noise than keeping 0.3 does (Q / 0.5 < Q / 0.3), so its predicted covariance
    is smaller; the local whose share fell from 0.7 to 0.5 gets a larger one."""
    moved = _run(data, _bank(ShareController(from_dict(constant_doc()), "constant"), (0.7, 0.3)))
    fixed = _run(data, _bank(beta=(0.7, 0.3)))
    assert moved.ok and fixed.ok
    # final local covariances: local 0 (share down) wider, local 1 (share up) narrower
    P_m, P_f = moved.locals.P_end, fixed.locals.P_end
    assert np.trace(P_m[0]) > np.trace(P_f[0])
    assert np.trace(P_m[1]) < np.trace(P_f[1])
