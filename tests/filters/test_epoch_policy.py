"""EpochPolicy: a policy stepped from Python reproduces the compiled loop's adaptation.

The reference is a real run of the filter loop on a short paper000 scenario: the loop is
given a kernel table in which the policy's kernel is wrapped by a recorder that stores what
the loop passed in (innovation, ``H P- H^T``, nominal R, motion context) and what the
kernel returned.  Replaying the recorded inputs through :class:`EpochPolicy` must give the
same R factors, weights and diagnostics bit for bit (the same compiled kernel on the same
numbers), and those must match the loop's own event log (its S diagonal and diagnostics),
which the recorder does not touch.
"""
import dataclasses
import json
from pathlib import Path

import numba as nb
import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError, UnknownNameError
from fuzzynav.filters import adaptation
from fuzzynav.filters.adaptation import ADAPT_SIG
from fuzzynav.filters.adaptation.epoch import EpochPolicy

MAXR = 6  # rows of a GNSS epoch
#: a recorded epoch: m, then from these offsets r, HPH, R, speed/rate/force, the kernel's
#: status and its out (weight, Q factor, R factors)
O_R, O_HPH = 1, 1 + MAXR
O_RN = O_HPH + MAXR * MAXR
O_CTX = O_RN + MAXR
O_STATUS = O_CTX + 3
O_OUT = O_STATUS + 1
BLOCK = O_OUT + 2 + MAXR
CAPACITY = 400  # epochs
GNSS_ROWS = ("pos",) * 3 + ("vel",) * 3
RULES = Path(__file__).resolve().parents[2] / "rules"


def _recorder(inner):
    """A kernel recording each call of ``inner`` into the tail of its state array (whose
    last entry holds the length of ``inner``'s own state)."""

    @nb.njit(ADAPT_SIG, error_model="numpy")
    def rec(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
        k = int(st[st.size - 1])
        n = int(st[k])
        b = k + 1 + n * BLOCK
        full = b + BLOCK > st.size - 1
        if not full:
            st[b] = m
            for i in range(m):
                st[b + O_R + i] = r[i]
                st[b + O_RN + i] = R[i]
                for j in range(m):
                    st[b + O_HPH + i * MAXR + j] = HPH[i, j]
            for i in range(3):
                st[b + O_CTX + i] = ctx[i]
        status = inner(fp, ip, st[:k], r, HPH, R, chan, m, out, diag, ctx)
        if not full:
            st[b + O_STATUS] = status
            for i in range(2 + m):
                st[b + O_OUT + i] = out[i]
            st[k] = n + 1
        return status

    return rec


def _record(log, filter_name, options, monkeypatch):
    """Run ``filter_name`` on the log's GNSS alone with its policy's kernel recorded.

    Returns the adapter, the recorded epochs (dicts) and the loop's event log."""
    from fuzzynav.experiment import run_on_log, setup_for
    from fuzzynav.filters import runner

    setup = setup_for(log, filter_name, options)
    adapter = setup.adapters["gps"]
    own = adapter.arrays

    def arrays(model):  # the policy's own arrays, then the recording buffer and its size
        fp, ip, st = own(model)
        tail = np.zeros(1 + CAPACITY * BLOCK + 1)
        tail[-1] = st.size
        return fp, ip, np.concatenate([st, tail])

    fns, index = adaptation.kernel_table()
    k = index[adapter.name]
    table = fns[:k] + (_recorder(fns[k]),) + fns[k + 1:]
    tables = runner.pack_sensors
    kept = []

    def keep_tables(*args):  # the loop mutates the flat state array of these tables
        kept.append(tables(*args))
        return kept[-1]

    monkeypatch.setattr(adapter, "arrays", arrays)
    monkeypatch.setattr(adaptation, "kernel_table", lambda used=None: (table, index))
    monkeypatch.setattr(runner, "pack_sensors", keep_tables)
    setup = dataclasses.replace(setup, adapters={"gps": adapter}, use_sensors=("gps",))
    res = run_on_log(log, filter_name, setup=setup).result
    monkeypatch.undo()
    sens = kept[-1].sensors
    assert res.ok and kept[-1].names == ["gps"]
    return adapter, _epochs(sens.ast[sens.ast_off[0]:sens.ast_off[1]]), res.events["gps"]


def _epochs(st):
    k = int(st[-1])
    n = int(st[k])
    assert 0 < n < CAPACITY
    out = []
    for e in range(n):
        b = st[k + 1 + e * BLOCK:k + 1 + (e + 1) * BLOCK]
        m = int(b[0])
        out.append({"r": b[O_R:O_R + m],
                    "HPH": b[O_HPH:O_RN].reshape(MAXR, MAXR)[:m, :m],
                    "R": b[O_RN:O_RN + m], "ctx": b[O_CTX:O_STATUS],
                    "status": int(b[O_STATUS]), "out": b[O_OUT:O_OUT + 2 + m]})
    return out


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    """The first 160 s of paper000 with outliers (rest, acceleration, cruise, a turn)."""
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario

    scn = load_scenario("paper000-outliers")
    scn = dataclasses.replace(scn, segments=scn.segments[:4])
    return simulate(scn, 1, tmp_path_factory.mktemp("sim"))


#: each case compiles a recorder around its kernel (1-5 s): three in the default run
CASES = [("fuzzy", {"rules": "paper000_select_gnss.json"}),      # r-scaling
         ("sage-husa", None), ("huber", None),
         pytest.param("fuzzy", {"rules": "paper000_rq_select_gnss.json"},  # motion inputs
                      marks=pytest.mark.slow),
         pytest.param("fuzzy", {"rules": "paper000_gps_sins.json"},  # exponential weighting
                      marks=pytest.mark.slow),
         pytest.param("vb", None, marks=pytest.mark.slow)]


@pytest.mark.parametrize("filter_name, options", CASES,
                         ids=lambda v: v["rules"].split(".")[0] if isinstance(v, dict) else v)
def test_replay_reproduces_the_compiled_loop(log, filter_name, options, monkeypatch):
    adapter, epochs, ev = _record(log, filter_name, options, monkeypatch)
    formed = np.flatnonzero(np.isfinite(ev.S_diag[:, 0]))  # epochs that reached the policy
    assert len(epochs) == formed.size > 100
    policy = EpochPolicy(adapter, GNSS_ROWS)
    assert policy.diag_names == ev.diag_names
    moved = False
    for rec, e in zip(epochs, formed):
        m = rec["r"].size
        assert m == 6
        np.testing.assert_array_equal(rec["r"], ev.residual[e, :m])  # the recorder's view
        speed, rate, force = rec["ctx"]
        step = policy.step(rec["r"], rec["HPH"], rec["R"],
                           context={"speed_m_s": speed, "angular_rate_rad_s": rate,
                                    "force_deviation_m_s2": force})
        # the kernel's own outputs in the loop, bit for bit
        assert step.status == rec["status"]
        assert step.p_weight == rec["out"][0] and step.q_scale == rec["out"][1]
        np.testing.assert_array_equal(step.r_scale, rec["out"][2:])
        # the loop's event log: S = H P- H^T + adapted R, and its diagnostics
        # numpy's sum here against the loop's compiled one: two code paths, so a tolerance
        np.testing.assert_allclose(np.diag(rec["HPH"]) + step.R, ev.S_diag[e, :m],
                                   rtol=1e-14, atol=0.0)
        np.testing.assert_array_equal(np.array(list(step.diag.values())), ev.diag[e])
        moved |= step.p_weight != 1.0 or np.any(step.r_scale != 1.0)
    assert moved, "the policy never adapted: the comparison would be vacuous"


def test_reset_starts_the_sequence_again():
    rng = np.random.default_rng(3)
    stream = [(rng.normal(0, 2, 6), np.eye(6) * 0.3, np.full(6, 1.0)) for _ in range(25)]
    policy = EpochPolicy.from_policy("sage-husa", GNSS_ROWS, b=0.9)
    first = [policy.step(*s).r_scale for s in stream]
    policy.reset()
    again = [policy.step(*s).r_scale for s in stream]
    np.testing.assert_array_equal(first, again)
    assert not np.allclose(first[0], first[-1])  # it is a running estimate


def test_sage_husa_matches_its_recursion_by_hand():
    """R_k = (1-d) R_{k-1} + d (r^2 - HPH), d_k = (1-b)/(1-b^(k+1)), from the nominal R."""
    b, R0, hph = 0.9, 2.0, 0.5
    rng = np.random.default_rng(4)
    policy = EpochPolicy.from_policy("sage-husa", ("pos",), b=b, floor=1e-6)
    Rh = R0
    for k, r in enumerate(rng.normal(0, 3, 30)):
        d = (1 - b) / (1 - b ** (k + 1))
        Rh = (1 - d) * Rh + d * (r * r - hph)
        Rh = max(Rh, 1e-6 * R0)
        step = policy.step([r], [[hph]], [R0])
        assert step.R[0] == pytest.approx(Rh, rel=1e-12)


def _constant_rules(tmp_path, value):
    """An r-scaling rule file with one rule, always fully fired, giving ``t = value``."""
    doc = json.loads((RULES / "paper002_ror.json").read_text())
    doc["inputs"][0]["terms"] = [{"name": "any", "mf": "trap", "params": [-1.0, -0.5, 3.5, 4.0]}]
    doc["outputs"][0]["terms"] = [{"name": "c", "mf": "tri",
                                   "params": [value - 0.1, value, value + 0.1]}]
    doc["rules"] = [{"if": {"ror": "any"}, "then": {"t": "c"}, "weight": 1.0}]
    path = tmp_path / "constant.json"
    path.write_text(json.dumps(doc))
    return path


def test_a_constant_rule_gives_a_geometric_scale(tmp_path):
    """t = 1.2 whatever the input (the centroid of a symmetric triangle; the engine's
    discretised centroid to 1e-9): the running factor is 1.2^k until its cap 1e3."""
    policy = EpochPolicy.from_rules(_constant_rules(tmp_path, 1.2), ("pos", "pos"))
    rng = np.random.default_rng(5)
    for k in range(1, 45):
        step = policy.step(rng.normal(0, 1, 2), np.eye(2), [1.0, 4.0])
        s = min(1.2 ** k, 1e3)
        assert step.diag["t"] == pytest.approx(1.2, rel=1e-9)
        np.testing.assert_allclose(step.r_scale, [s, s], rtol=1e-8)
        np.testing.assert_allclose(step.R, [s, 4 * s], rtol=1e-8)
    assert step.r_scale[0] == 1e3


def test_every_per_sensor_policy_the_loop_knows_can_be_stepped():
    """A new fuzzy policy fails here ("run by a rule file") until a rule file is named."""
    names = set(adaptation.ADAPTERS.load())
    fuzzy = {"exponential-weighting": "paper000_gps_sins.json",
             "r-scaling": "paper002_ror_gnss.json", "rq-scaling": "paper000_rq_gnss.json",
             "fuzzy-sage-husa": "supervisor_sage_husa.json", "fuzzy-vb": "supervisor_vb.json",
             "fuzzy-huber": "supervisor_huber.json"}
    for name in sorted(names):
        policy = (EpochPolicy.from_rules(fuzzy[name], GNSS_ROWS) if name in fuzzy
                  else EpochPolicy.from_policy(name, GNSS_ROWS))
        assert policy.name == name
        step = policy.step(np.full(6, 0.5), np.eye(6), np.ones(6))
        assert step.r_scale.shape == (6,) and np.all(step.r_scale > 0)
        assert step.p_weight > 0 and step.q_scale > 0


def test_the_policy_is_the_loops_kernel_not_a_bound_method():
    policy = EpochPolicy.from_policy("huber", ("pos",))
    fns, index = adaptation.kernel_table()
    assert policy._kernel is fns[index["huber"]]


@pytest.mark.parametrize("args, match", [
    ((np.ones(3), np.eye(2), np.ones(2)), "innovation: must be 2"),
    ((np.ones(2), np.eye(3), np.ones(2)), r"hph: must be a finite \(2, 2\)"),
    ((np.ones(2), np.eye(2), np.ones(3)), "R: must be 2"),
    ((np.ones(2), np.eye(2), np.ones((2, 2))), "diagonal"),
    ((np.ones(2), np.eye(2), [1.0, -1.0]), "positive"),
    ((np.array([1.0, np.nan]), np.eye(2), np.ones(2)), "innovation"),
    ((np.ones(2), "eye", np.ones(2)), "hph: must be numbers"),
])
def test_bad_sizes_are_one_clear_error(args, match):
    policy = EpochPolicy.from_policy("sage-husa", ("pos", "vel"))
    with pytest.raises(FuzzynavError, match=match):
        policy.step(*args)


def test_bad_construction_is_one_clear_error(tmp_path):
    with pytest.raises(UnknownNameError, match="unknown adaptation policy 'kalman-magic'"):
        EpochPolicy.from_policy("kalman-magic", ("pos",))
    with pytest.raises(FuzzynavError, match="run by a rule file"):
        EpochPolicy.from_policy("r-scaling", ("pos",))
    with pytest.raises(FuzzynavError, match="bad parameters"):
        EpochPolicy.from_policy("huber", ("pos",), gama=2.0)
    with pytest.raises(FuzzynavError, match="information shares"):
        EpochPolicy.from_rules("paper001_beta.json", ("pos",))
    with pytest.raises(UnknownNameError, match="channel of the gnss model 'heading'"):
        EpochPolicy.from_policy("huber", ("heading",), model="gnss")
    with pytest.raises(FuzzynavError, match="at most 6"):
        EpochPolicy.from_policy("huber", ("pos",) * 7)
    with pytest.raises(FuzzynavError, match="registered adaptation policy"):
        EpochPolicy(object(), ("pos",))
    with pytest.raises(InputFileError, match="paper000_gps_sins.json.*no channel 'pos'"):
        EpochPolicy.from_rules("paper000_gps_sins.json", ("pos",), model="nhc")


def test_context_the_rule_file_reads_is_required():
    policy = EpochPolicy.from_rules("paper000_rq_select_gnss.json", GNSS_ROWS)
    args = (np.ones(6), np.eye(6), np.ones(6))
    with pytest.raises(FuzzynavError, match="reads speed_m_s, angular_rate_rad_s"):
        policy.step(*args)
    with pytest.raises(FuzzynavError, match="unknown key.*speed_kmh"):
        policy.step(*args, context={"speed_kmh": 3.0})
    ctx = {"speed_m_s": 10.0, "angular_rate_rad_s": 0.1, "force_deviation_m_s2": 0.0}
    assert policy.step(*args, context=ctx).q_scale > 0
    # the quality columns land where the gnss model's data row has them
    q = EpochPolicy.from_rules("recording_rq_quality_gnss.json", GNSS_ROWS)
    assert set(q.needs) >= {"fix_type", "n_sat"}
    with pytest.raises(FuzzynavError, match="reads fix_type, n_sat"):
        q.step(*args, context=ctx)
    q.step(*args, context={**ctx, "fix_type": 1, "n_sat": 12})
