"""Adaptation policies: statistics, the fuzzy bindings and the classical estimators."""
import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import classical, window
from fuzzynav.filters.adaptation.exponential_weighting import FuzzyExponentialWeighting
from fuzzynav.filters.adaptation.r_scaling import FuzzyRScaling
from fuzzynav.filters.catalog import bind_rule_files, bind_systems
from fuzzynav.fuzzy import load_fis

GNSS = measurements.get("gnss")
RULES = "rules/paper000_gps_sins.json"


def _epoch(rng, m=6, r_scale=1.0):
    HPH = np.diag(rng.uniform(0.5, 2.0, m))
    R = rng.uniform(0.5, 2.0, m)
    r = rng.normal(0.0, np.sqrt((np.diag(HPH) + R) * r_scale))
    chan = np.array([0, 0, 0, 1, 1, 1][:m], np.int64)
    return r, HPH, R, chan


def _call(bound, r, HPH, R, chan):
    fns, _ = adaptation.kernel_table()
    out, diag = np.zeros(2 + r.size), np.zeros(adaptation.N_DIAG)
    st = fns[bound.kernel_id](bound.fp, bound.ip, bound.state, r, HPH, R.copy(), chan, r.size,
                              out, diag, np.zeros(32))
    return out, diag, st


def test_window_statistics_match_their_definitions():
    rng = np.random.default_rng(0)
    n, c = 5, 2
    st = np.zeros(window.window_size(n, c))
    sums = []
    for _ in range(8):
        r, HPH, R, chan = _epoch(rng)
        window.push(st, 0, n, c, r, chan, r.size)
        sums.append([np.sum(r[:3] ** 2), np.sum(r[3:] ** 2), np.sum(r ** 2)])
    last = np.array(sums[-n:])
    for ch, col in ((0, 0), (1, 1), (-1, 2)):
        assert window.trace_actual(st, 0, n, c, ch) == pytest.approx(last[:, col].mean())
    th = np.sum(np.diag(HPH)[:3] + R[:3])
    act = last[:, 0].mean()
    assert window.statistic(0, st, 0, n, c, HPH, R, chan, 6, 0) == pytest.approx((th - act) / th)
    assert window.statistic(1, st, 0, n, c, HPH, R, chan, 6, 0) == pytest.approx(act / th)


def test_dom_is_near_zero_and_ror_near_one_for_a_consistent_stream():
    rng = np.random.default_rng(1)
    n = 20
    st = np.zeros(window.window_size(n, 2))
    dom, ror = [], []
    for _ in range(3000):
        r, HPH, R, chan = _epoch(rng)
        window.push(st, 0, n, 2, r, chan, 6)
        dom.append(window.statistic(0, st, 0, n, 2, HPH, R, chan, 6, 0))
        ror.append(window.statistic(1, st, 0, n, 2, HPH, R, chan, 6, -1))
    assert abs(np.mean(dom[n:])) < 0.05 and abs(np.mean(ror[n:]) - 1.0) < 0.05


def test_exponential_weighting_evaluates_the_rule_file_on_the_statistics():
    fis = load_fis(RULES)
    bound = FuzzyExponentialWeighting(fis, RULES).bind(GNSS)
    rng = np.random.default_rng(2)
    n = fis.binding["window"]
    ref_st = np.zeros(window.window_size(n, 2))
    for _ in range(30):
        r, HPH, R, chan = _epoch(rng, r_scale=3.0)
        out, diag, _ = _call(bound, r, HPH, R, chan)
        window.push(ref_st, 0, n, 2, r, chan, 6)
        x = [window.statistic(0, ref_st, 0, n, 2, HPH, R, chan, 6, c) for c in (0, 1)]
        alpha = fis.evaluate({"dom_pos": x[0], "dom_vel": x[1]})["alpha"]
        assert diag[0] == pytest.approx(alpha, rel=1e-12)
        assert out[0] == pytest.approx(alpha ** 2) and np.allclose(out[2:], 1 / alpha ** 2)
        assert np.allclose(diag[1:3], x)


def test_r_scaling_accumulates_and_is_bounded():
    fis = load_fis("rules/paper002_ror_gnss.json")
    bound = FuzzyRScaling(fis, "ror").bind(GNSS)
    rng = np.random.default_rng(3)
    s_prev = 1.0
    for _ in range(400):  # innovations 30x too large: R must grow, step by step, up to the cap
        r, HPH, R, chan = _epoch(rng, r_scale=30.0)
        out, diag, _ = _call(bound, r, HPH, R, chan)
        assert diag[0] == pytest.approx(s_prev * diag[1], rel=1e-12) or diag[0] == 1e3
        assert np.allclose(out[2:8], diag[0])
        s_prev = diag[0]
    assert s_prev > 10.0


def test_sage_husa_and_vb_converge_to_the_true_noise():
    rng = np.random.default_rng(4)
    for policy in (classical.SageHusa(b=0.995), classical.VariationalBayes(rho=0.995)):
        bound = policy.bind(GNSS)
        scales = []
        for _ in range(3000):
            HPH = np.diag(np.full(6, 0.2))
            R = np.ones(6)
            r = rng.normal(0.0, np.sqrt(0.2 + 4.0), 6)  # the true R is 4x the nominal
            out, _, _ = _call(bound, r, HPH, R, np.zeros(6, np.int64))
            scales.append(out[2:8].mean())
        assert np.mean(scales[-500:]) == pytest.approx(4.0, rel=0.15), policy.name


def test_huber_weights():
    bound = classical.Huber(gamma=1.0).bind(GNSS)
    HPH, R = np.diag([0.5, 0.5]), np.array([0.5, 0.5])
    out, diag, _ = _call(bound, np.array([0.5, 3.0]), HPH, R, np.zeros(2, np.int64))
    assert out[2] == 1.0 and out[3] == pytest.approx(3.0)   # |zeta| = 3 > gamma: R x 3
    assert diag[0] == pytest.approx(1 / 3)


def test_fading_memory_stays_at_one_when_consistent_and_grows_when_not():
    rng = np.random.default_rng(5)
    for scale, check in ((1.0, lambda lam: np.mean(lam) < 1.05), (20.0, lambda lam: np.mean(lam) > 1.5)):
        bound = classical.FadingMemory().bind(GNSS)
        lam = []
        for _ in range(400):
            HPH = np.diag(np.full(6, 1.0))
            r = rng.normal(0.0, np.sqrt(1.0 + 1.0 * scale), 6)
            lam.append(_call(bound, r, HPH, np.ones(6), np.zeros(6, np.int64))[0][0])
        assert check(lam[50:])


def test_binding_errors_name_the_file_and_field(tmp_path):
    d = load_fis(RULES).to_dict()
    d["binding"]["inputs"]["dom_pos"] = {"statistic": "median", "channel": "pos"}
    with pytest.raises(InputFileError, match=r"x\.json: \$\.binding\.inputs\.dom_pos\.statistic"):
        FuzzyExponentialWeighting(load_fis(d), "x.json")
    d = load_fis(RULES).to_dict()
    d["binding"]["adapter"] = "r-scaling"
    with pytest.raises(InputFileError, match=r"\$\.binding\.adapter"):
        FuzzyExponentialWeighting(load_fis(d), "x.json")


def test_rules_bind_to_the_sensor_with_their_channels():
    from fuzzynav.sim.sensors import SensorData

    gnss = SensorData("gnss", np.zeros(1), np.zeros((1, 6)), np.ones((1, 6)))
    pol = SensorData("polarization", np.zeros(1), np.zeros((1, 4)), np.ones((1, 4)))
    bound = bind_rule_files(["paper000_gps_sins.json", "paper000_attitude.json"],
                            {"gps": gnss, "pol": pol})
    assert set(bound) == {"gps", "pol"}
    with pytest.raises(FuzzynavError, match="no sensor of this run provides"):
        bind_rule_files(["paper000_attitude.json"], {"gps": gnss})
    assert bind_systems([(load_fis("rules/paper000_attitude.json"), "a")], {"gps": gnss},
                        required=False) == {}
