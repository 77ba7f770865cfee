"""Zhou's strong tracking factor and the named filters with tuned parameters."""
import json
import math

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation.strong_tracking import StrongTracking
from fuzzynav.filters.baselines import hqh_per_channel
from fuzzynav.filters.params_file import PARAMS_FORMAT
from fuzzynav.filters.named import FilterContext, get_filter, parse_filter_spec

GNSS = measurements.get("gnss")


def _lambdas(policy, epochs):
    """Drive a policy's kernel over ``(r, R, HPH diagonal)`` epochs of a pos+vel row pair."""
    bound = policy.bind(GNSS)
    fns, _ = adaptation.kernel_table()
    chan = np.array([0, 1], np.int64)
    lams = []
    for r, R, hph in epochs:
        out, diag = np.zeros(4), np.zeros(adaptation.N_DIAG)
        fns[bound.kernel_id](bound.fp, bound.ip, bound.state, np.array(r, float),
                             np.diag(np.array(hph, float)), np.array(R, float), chan, 2, out,
                             diag, np.zeros(32))
        assert out[1] == 1.0 and out[2] == 1.0 and out[3] == 1.0  # only P is weighted
        lams.append(out[0])
    return lams


EPOCHS = [([3.0, 1.0], [1.0, 0.5], [2.0, 1.0]),
          ([1.0, 0.0], [1.0, 0.5], [2.0, 1.0])]


def test_strong_tracking_matches_a_hand_computed_case():
    # rho 0.5, beta 2, H Q H^T 0.1 (pos) and 0.2 (vel).
    # epoch 1: V0 = r r^T = diag(9, 1); N = (9 - 2 - 0.1) + (1 - 1 - 0.2) = 6.7,
    #          M = (2 - 0.1) + (1 - 0.2) = 2.7  ->  lambda = 6.7 / 2.7
    # epoch 2: V0 = (0.5 V0 + r r^T) / 1.5 = diag(5.5/1.5, 0.5/1.5);
    #          N = (11/3 - 2.1) + (1/3 - 1.2) = 0.7 < M  ->  lambda = 1
    policy = StrongTracking(rho=0.5, beta=2.0, hqh={"pos": 0.1, "vel": 0.2})
    lams = _lambdas(policy, EPOCHS)
    assert lams[0] == pytest.approx(6.7 / 2.7, rel=1e-12)
    assert lams[1] == pytest.approx(1.0, rel=1e-12)


def test_strong_tracking_cap_and_the_process_noise_it_removes():
    capped = _lambdas(StrongTracking(rho=0.5, beta=2.0, lam_max=2.0,
                                     hqh={"pos": 0.1, "vel": 0.2}), EPOCHS[:1])
    assert capped[0] == pytest.approx(2.0)
    # without H Q H^T removed: N = 7 + 0 = 7, M = 3 -> 7/3 (the fading-memory-like form)
    plain = _lambdas(StrongTracking(rho=0.5, beta=2.0), EPOCHS[:1])
    assert plain[0] == pytest.approx(7.0 / 3.0, rel=1e-12)


def test_hqh_per_channel_is_the_white_imu_noise_over_an_epoch():
    from fuzzynav import units
    from fuzzynav.filters.config import FilterConfig

    cfg = FilterConfig(arw_dpsh=0.2, vrw_ug_psqrthz=50.0)
    data = _stream(np.arange(0.0, 10.0, 0.5))
    q = hqh_per_channel(cfg, data)
    qv = (50.0 * units.UG) ** 2
    assert q["vel"] == pytest.approx(qv * 0.5)
    assert q["pos"] == pytest.approx(qv * 0.5**3 / 3)


def _params_file(tmp_path, filters):
    p = tmp_path / "b.json"
    p.write_text(json.dumps({"format": PARAMS_FORMAT, "version": 1, "filters": filters}))
    return p


def _stream(time_s):
    """A GNSS stream as the named filters see it (kind and epoch times)."""
    return type("Stream", (), {"kind": "gnss", "time_s": time_s})()


def _ctx(options):
    sensors = {"gps": _stream(np.arange(5.0))}
    return FilterContext(imu_noise=None, sensors=sensors, options=options)


def test_ekf_tuned_applies_the_file_multipliers(tmp_path):
    p = _params_file(tmp_path, {"ekf-tuned": {"q_vel": 4.0, "q_att": 0.25, "r_pos": 6.0}})
    name, opts = parse_filter_spec(f"ekf-tuned@{p}")
    assert opts == {"params": str(p)}
    setup = get_filter(name).make(_ctx(opts))
    base = get_filter("ekf").make(_ctx({})).config
    assert setup.config.vrw_ug_psqrthz == pytest.approx(2.0 * base.vrw_ug_psqrthz)
    assert setup.config.arw_dpsh == pytest.approx(0.5 * base.arw_dpsh)
    fp, _, _ = setup.adapters["gps"].arrays(GNSS)
    assert list(fp) == [6.0, 1.0]  # pos scaled, vel (not in the file) nominal


def test_tuned_filters_refuse_bad_or_missing_parameters(tmp_path):
    p = _params_file(tmp_path, {"ekf-tuned": {"r_pos": -1.0}})
    with pytest.raises(InputFileError, match=r"\$\.filters\.ekf-tuned\.r_pos"):
        get_filter("ekf-tuned").make(_ctx({"params": str(p)}))
    good = _params_file(tmp_path, {"ekf-tuned": {"r_pos": 2.0}})
    with pytest.raises(InputFileError, match=r"\$\.filters\.vb-tuned.*missing"):
        get_filter("vb-tuned").make(_ctx({"params": str(good)}))
    bad = tmp_path / "x.json"
    bad.write_text('{"format": "other"}')
    with pytest.raises(InputFileError, match=r"\$\.format"):
        get_filter("huber-tuned").make(_ctx({"params": str(bad)}))
    with pytest.raises(FuzzynavError, match="not found"):
        get_filter("ekf-tuned").make(_ctx({"params": str(tmp_path / "none.json")}))


def test_sage_husa_tuned_passes_its_bounds(tmp_path):
    p = _params_file(tmp_path, {"sage-husa-tuned": {"b": 0.9, "floor": 0.5, "cap": 3.0}})
    setup = get_filter("sage-husa-tuned").make(_ctx({"params": str(p)}))
    fp, _, _ = setup.adapters["gps"].arrays(GNSS)
    assert list(fp) == [0.9, 0.5, 3.0]
    # the cap bounds the estimate: a huge residual gives at most cap x nominal
    bound = setup.adapters["gps"].bind(GNSS)
    fns, _ = adaptation.kernel_table()
    out = np.zeros(4)
    fns[bound.kernel_id](bound.fp, bound.ip, bound.state, np.array([100.0, 0.0]),
                         np.eye(2), np.ones(2), np.array([0, 1], np.int64), 2, out,
                         np.zeros(adaptation.N_DIAG), np.zeros(32))
    assert out[2] == pytest.approx(3.0) and out[3] == pytest.approx(0.5)
    assert math.isfinite(out[0])
