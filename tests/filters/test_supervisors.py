"""Fuzzy supervisors of the classical adaptive filters (issue 25).

* With a rule file whose output is the parent's constant, each supervisor gives its parent's
  run bit for bit on a short paper000 scenario.  The constant system is one Sugeno rule whose
  antecedent term is 1 over the whole input range: the weighted average ``1*c / 1`` is
  exactly ``c`` (an average over several equal consequents may differ from ``c`` by an ulp).
* A non-constant controller (speed -> parameter, two triangular terms) sets the parameter
  per epoch as the closed form of its Sugeno output says; Sage-Husa's estimate follows the
  variable-``b`` recursion ``W_k = 1 + b_k W_(k-1)``, ``d_k = 1 / W_k``, computed here.
"""
import dataclasses
import math

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.adaptation.supervisors import FuzzyHuber, FuzzySageHusa, FuzzyVB
from fuzzynav.fuzzy.io import from_dict

GNSS = measurements.get("gnss")
SPEED_MAX = 20.0


def _system(adapter, out, rng, terms, input_terms, statistic="speed", in_range=None):
    lo, hi = in_range or (0.0, SPEED_MAX)
    return from_dict({
        "format": "fuzzynav-fis", "version": 1, "name": "s", "type": "sugeno",
        "operators": {"and": "min", "or": "max", "defuzzifier": "wtaver"},
        "inputs": [{"name": "u", "range": [lo, hi], "terms": input_terms}],
        "outputs": [{"name": out, "range": rng, "terms": [
            {"name": f"c{j}", "mf": "constant", "params": [c]} for j, c in enumerate(terms)]}],
        "rules": [{"if": {"u": t["name"]}, "then": {out: f"c{j}"}}
                  for j, t in enumerate(input_terms)],
        "binding": {"adapter": adapter, "inputs": {"u": {"statistic": statistic}},
                    "outputs": {out: out}, "sensor": "gnss"}})


def constant_system(adapter, out, rng, c):
    """One always-firing rule: the output is exactly ``c``."""
    return _system(adapter, out, rng, [c], [{"name": "any", "mf": "trap",
                                             "params": [-1.0, 0.0, SPEED_MAX, SPEED_MAX + 1]}])


def speed_system(adapter, out, rng, c_slow, c_fast):
    """``y(v) = c_slow (1 - v/20) + c_fast v/20`` on [0, 20] m/s (two strong triangles)."""
    return _system(adapter, out, rng, [c_slow, c_fast], [
        {"name": "slow", "mf": "tri", "params": [-SPEED_MAX, 0.0, SPEED_MAX]},
        {"name": "fast", "mf": "tri", "params": [0.0, SPEED_MAX, 2 * SPEED_MAX]}])


def _drive(policy, speeds, rng):
    """Kernel outputs and diagnostics on GNSS epochs with random residuals at given speeds."""
    bound = policy.bind(GNSS)
    fns, _ = adaptation.kernel_table()
    chan = np.array([0, 0, 0, 1, 1, 1], np.int64)
    hph, R = np.diag(np.full(6, 0.5)), np.array([1.0, 1.0, 4.0, 0.1, 0.1, 0.2])
    rows = []
    for v in speeds:
        r = rng.normal(0.0, 2.0, 6)
        out, diag, ctx = np.zeros(8), np.zeros(adaptation.N_DIAG), np.zeros(32)
        ctx[0] = v
        fns[bound.kernel_id](bound.fp, bound.ip, bound.state, r, hph.copy(), R.copy(), chan,
                             6, out, diag, ctx)
        rows.append((r, out.copy(), diag.copy()))
    return rows, hph, R


SPEEDS = [0.0, 5.0, 12.0, 20.0, 3.0, 3.0]


def test_fuzzy_sage_husa_follows_its_rules_and_the_variable_b_recursion():
    fis = speed_system("fuzzy-sage-husa", "b", [0.8, 1.0], 0.99, 0.9)
    rows, hph, R = _drive(FuzzySageHusa(fis, "t", floor=0.01, cap=1e6), SPEEDS,
                          np.random.default_rng(3))
    w, rh = 0.0, R.copy()
    for v, (r, out, diag) in zip(SPEEDS, rows):
        b = 0.99 * (1 - v / SPEED_MAX) + 0.9 * v / SPEED_MAX
        assert diag[1] == pytest.approx(b, rel=1e-14)
        w = 1.0 + b * w
        rh = (1 - 1 / w) * rh + (r * r - np.diag(hph)) / w
        rh = np.clip(rh, 0.01 * R, 1e6 * R)
        np.testing.assert_allclose(out[2:], rh / R, rtol=1e-12)
        assert out[0] == 1.0 and out[1] == 1.0


def test_fuzzy_huber_sets_gamma_per_epoch():
    fis = speed_system("fuzzy-huber", "gamma", [0.5, 5.0], 3.0, 1.0)
    rows, hph, R = _drive(FuzzyHuber(fis, "t"), SPEEDS, np.random.default_rng(4))
    for v, (r, out, diag) in zip(SPEEDS, rows):
        gamma = 3.0 * (1 - v / SPEED_MAX) + 1.0 * v / SPEED_MAX
        assert diag[1] == pytest.approx(gamma, rel=1e-14)
        zeta = np.abs(r) / np.sqrt(np.diag(hph) + R)
        np.testing.assert_allclose(out[2:], np.maximum(1.0, zeta / gamma), rtol=1e-12)
        assert diag[0] == pytest.approx(min(1.0, (gamma / zeta).min()), rel=1e-12)


def test_fuzzy_vb_sets_rho_per_epoch():
    """rho_k as the rules say; with one row and no prior uncertainty (HPH = 0) VB's
    posterior is closed: a_k = rho a + 1/2, b_k = rho b + r^2/2, R = b/a."""
    fis = speed_system("fuzzy-vb", "rho", [0.5, 1.0], 0.99, 0.6)
    policy = FuzzyVB(fis, "t", iterations=2)
    bound = policy.bind(GNSS)
    fns, _ = adaptation.kernel_table()
    a, bb, R0 = 2.0, 2.0, 1.0
    for k, v in enumerate(SPEEDS):
        rho = 0.99 * (1 - v / SPEED_MAX) + 0.6 * v / SPEED_MAX
        r = np.array([1.0 + k])
        out, diag, ctx = np.zeros(3), np.zeros(adaptation.N_DIAG), np.zeros(32)
        ctx[0] = v
        fns[bound.kernel_id](bound.fp, bound.ip, bound.state, r, np.zeros((1, 1)),
                             np.array([R0]), np.zeros(1, np.int64), 1, out, diag, ctx)
        a, bb = rho * a + 0.5, rho * bb + 0.5 * r[0] ** 2
        assert diag[1] == pytest.approx(rho, rel=1e-14)
        assert out[2] == pytest.approx(bb / a / R0, rel=1e-12)


@pytest.mark.parametrize("cls, target, lo", [(FuzzySageHusa, "b", -0.1),
                                             (FuzzyVB, "rho", 0.5),
                                             (FuzzyHuber, "gamma", 0.0)])
def test_an_output_range_outside_the_parameter_domain_is_refused(cls, target, lo):
    hi = 1.5 if target != "gamma" else 2.0
    fis = speed_system(cls.name, target, [lo, hi], lo, hi)
    with pytest.raises(InputFileError, match=rf"{target}.*outside what"):
        Binding.of(fis, "bad.json", cls.name)


# -- bit for bit with the parent on a short paper000 run -------------------------------------
PARENTS = [("fuzzy-sage-husa", "sage-husa", "b", [0.9, 1.0], 0.98, {}),
           ("fuzzy-vb", "vb", "rho", [0.9, 1.0], 0.98, {}),
           ("fuzzy-huber", "huber", "gamma", [0.5, 5.0], 1.345, {})]


@pytest.fixture(scope="module")
def short_log(sim_cache):
    from fuzzynav.sim.scenario import load_scenario
    from fuzzynav.sim.sensor_log import simulate

    scn = load_scenario("paper000-nominal")
    return simulate(dataclasses.replace(scn, segments=scn.segments[:4]), 0, sim_cache)


@pytest.mark.parametrize("name, parent, target, rng, c, opts", PARENTS)
def test_a_constant_supervisor_is_its_parent_bit_for_bit(short_log, tmp_path, name, parent,
                                                         target, rng, c, opts):
    from fuzzynav.experiment import run_on_log
    from fuzzynav.fuzzy import save_fis

    path = tmp_path / "const.json"
    save_fis(constant_system(name, target, rng, c), path)
    a = run_on_log(short_log, parent).result
    b = run_on_log(short_log, name, {"rules": [str(path)], **opts}).result
    assert a.ok and b.ok
    for field in ("lla", "vel_n", "q_bn", "sigma"):
        assert np.array_equal(getattr(a, field), getattr(b, field), equal_nan=True), field
    for sensor, ev in a.events.items():
        assert np.array_equal(ev.nis, b.events[sensor].nis, equal_nan=True), sensor
    # the supervisor did run and logged the parent's constant on the GNSS epochs
    gnss = [s for s, ev in b.events.items() if target in ev.diag_names]
    assert gnss and np.all(b.events[gnss[0]].diag[:, 1] == c)
    # a controller that moves the parameter does change the run
    moved = tmp_path / "moved.json"
    save_fis(constant_system(name, target, rng, rng[0] + 0.5 * (c - rng[0])), moved)
    m = run_on_log(short_log, name, {"rules": [str(moved)]}).result
    assert not np.array_equal(a.lla, m.lla) and not math.isnan(m.lla[-1, 0])


# -- the tuned parent's constants in the rule file (binding.parent) ---------------------------
TUNED_PARENTS = [("fuzzy-sage-husa", "sage-husa-tuned", "b", [0.9, 1.0],
                  {"b": 0.95, "floor": 0.5, "cap": 20.0}),
                 ("fuzzy-vb", "vb-tuned", "rho", [0.9, 1.0], {"rho": 0.93, "iterations": 2}),
                 ("fuzzy-huber", "huber-tuned", "gamma", [0.5, 5.0], {"gamma": 2.2})]


def _with_parent(fis, parent):
    return dataclasses.replace(fis, binding={**fis.binding, "parent": parent})


@pytest.mark.parametrize("name, tuned, target, rng, constants", TUNED_PARENTS)
def test_a_constant_supervisor_with_binding_parent_is_the_tuned_parent(
        short_log, tmp_path, name, tuned, target, rng, constants):
    """The parent's constants come from the rule file: with the output at the tuned
    constant, the run is the tuned parent's (read from a tuned-parameter file) bit for bit."""
    import json

    from fuzzynav.experiment import run_on_log
    from fuzzynav.fuzzy import save_fis

    params = tmp_path / "params.json"
    params.write_text(json.dumps({"format": "fuzzynav-baselines", "version": 1,
                                  "filters": {tuned: constants}}))
    rules = tmp_path / "const.json"
    save_fis(_with_parent(constant_system(name, target, rng, constants[target]), constants),
             rules)
    a = run_on_log(short_log, tuned, {"params": str(params)}).result
    b = run_on_log(short_log, name, {"rules": [str(rules)]}).result
    assert a.ok and b.ok
    assert np.array_equal(a.lla, b.lla) and np.array_equal(a.sigma, b.sigma, equal_nan=True)
    if len(constants) > 1:  # without binding.parent: the parent's defaults, another run
        plain = tmp_path / "plain.json"
        save_fis(constant_system(name, target, rng, constants[target]), plain)
        d = run_on_log(short_log, name, {"rules": [str(plain)]}).result
        assert not np.array_equal(a.lla, d.lla)


@pytest.mark.parametrize("parent, where", [({"b": 0.95, "floor": 0.5}, "$.binding.parent"),
                                           ({"b": 1.5, "floor": 0.5, "cap": 20.0},
                                            "$.binding.parent.b"),
                                           ({"b": 0.9, "floor": 0.5, "cap": 20.0, "x": 1},
                                            "$.binding.parent.x")])
def test_a_bad_binding_parent_is_refused_naming_the_key(parent, where):
    fis = _with_parent(constant_system("fuzzy-sage-husa", "b", [0.9, 1.0], 0.95), parent)
    with pytest.raises(InputFileError) as err:
        Binding.of(fis, "f.json")
    assert err.value.where == where


def test_binding_parent_only_on_a_supervisor_and_written_back():
    ok = _with_parent(constant_system("fuzzy-huber", "gamma", [0.5, 5.0], 2.0), {"gamma": 2.0})
    b = Binding.of(ok, "f.json")
    assert b.parent == (("gamma", 2.0),) and b.to_dict()["parent"] == {"gamma": 2.0}
    assert "parent" not in Binding.of(constant_system("fuzzy-huber", "gamma", [0.5, 5.0], 2.0),
                                      "f.json").to_dict()
    from fuzzynav.fuzzy import load_fis

    other = load_fis("rules/paper002_ror_gnss.json")
    with pytest.raises(InputFileError, match="no fuzzy supervisor"):
        Binding.of(_with_parent(other, {"gamma": 2.0}), "g.json")
