"""Search space: sorted breakpoints inside the range, strong partitions, conditional names,
``tune`` modes against the template file, rebuilding a trial's systems from its params."""
from __future__ import annotations

import itertools
import json

import numpy as np
import optuna
import pytest
import skfuzzy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fuzzynav.fuzzy import load_fis
from fuzzynav.tuning.controller_config import ControllerConfig
from fuzzynav.tuning.space import ControllerSpace, build_all
from tests.tuning.studies import ATT, GPS, ROR_GNSS

optuna.logging.set_verbosity(optuna.logging.ERROR)


class DrawTrial:
    """An Optuna-like trial whose every suggestion hypothesis draws (bounds included)."""

    def __init__(self, data):
        self.data = data
        self.params = {}

    def _keep(self, name, value):
        self.params[name] = value
        return value

    def suggest_float(self, name, lo, hi):
        return self._keep(name, self.data.draw(st.floats(lo, hi), label=name))

    def suggest_int(self, name, lo, hi):
        return self._keep(name, self.data.draw(st.integers(lo, hi), label=name))

    def suggest_categorical(self, name, choices):
        return self._keep(name, self.data.draw(st.sampled_from(choices), label=name))


def controller(template=GPS, name="gps", **kw) -> ControllerConfig:
    kw.setdefault("partitions", {"dom_pos": (3, 5), "dom_vel": (2, 3, 7), "alpha": (3, 4)})
    return ControllerConfig(name=name, template=template, **kw)


CONFIGS = {
    "both": controller(window=(5, 40), output_range=(1.01, 1.5)),
    "free": controller(free_triangles=True, rule_weights=True, output_low=(0.6, 0.99),
                       output_range=(1.05, 1.4)),
    "rules": controller(tune="rules", window=(3, 9)),
    "breakpoints": controller(tune="breakpoints", partitions={}, output_range=(1.2, 2.0)),
    "ror": controller(template=ROR_GNSS, partitions={"ror": (3, 5, 7), "t": (3, 5)},
                      output_low=(0.5, 0.95), output_range=(1.05, 2.0), window=(3, 40)),
}


def peaks(var):
    return np.array([t.params[1] for t in var.terms])


def degrees(var, x):
    """Membership degrees of every term on x, by scikit-fuzzy (an independent reference)."""
    return np.array([skfuzzy.trimf(x, list(t.params)) for t in var.terms])


def expected_names(cc, fis) -> set:
    """The parameter names a trial of this structure must have, enumerated independently."""
    tmpl = load_fis(cc.template)
    p = f"{cc.name}."
    names = set()
    counts = {}
    for v_t, v in zip(tmpl.inputs + tmpl.outputs, fis.inputs + fis.outputs):
        n = len(v.terms)
        counts[v.name] = n
        if len(cc.partitions.get(v.name, (len(v_t.terms),))) > 1:
            names.add(f"{p}n.{v.name}")
        if cc.tune != "rules":
            names |= {f"{p}gap.{v.name}.{n}.{k}" for k in range(n - 1)}
        if cc.free_triangles and cc.tune != "rules":
            names |= {f"{p}spread.{v.name}.{n}.{k}.{s}" for k in range(n) for s in "lr"}
    n_in = [counts[v.name] for v in tmpl.inputs]
    struct = "x".join(map(str, n_in)) + f">{counts[tmpl.outputs[0].name]}"
    if cc.tune != "breakpoints":
        for cell in itertools.product(*[range(c) for c in n_in]):
            key = ".".join(map(str, cell))
            names.add(f"{p}rule.{struct}.{key}")
            if cc.rule_weights:
                names.add(f"{p}weight.{struct}.{key}")
    elif cc.rule_weights:
        names |= {f"{p}weight.rule.{i}" for i in range(len(tmpl.rules))}
    if cc.window:
        names.add(f"{p}window")
    if cc.output_range:
        names.add(f"{p}out_hi")
    if cc.output_low:
        names.add(f"{p}out_lo")
    return names


def check_system(cc, fis, params):
    """Every invariant of a built system (shared by the hypothesis and Optuna tests)."""
    tmpl = load_fis(cc.template)
    out_t, out = tmpl.outputs[0], fis.outputs[0]
    # the output range and the window land in the system
    lo = params.get(f"{cc.name}.out_lo", out_t.range[0])
    hi = params.get(f"{cc.name}.out_hi", out_t.range[1])
    assert out.range == (lo, hi)
    if cc.output_range:
        assert cc.output_range[0] <= hi <= cc.output_range[1]
    if cc.output_low:
        assert cc.output_low[0] <= lo <= cc.output_low[1]
    assert fis.binding.get("window") == params.get(f"{cc.name}.window",
                                                   tmpl.binding.get("window"))
    for v_t, v in zip(tmpl.inputs + tmpl.outputs, fis.inputs + fis.outputs):
        allowed = cc.partitions.get(v.name, (len(v_t.terms),))
        assert len(v.terms) in allowed
        lo, hi = v.range
        p = peaks(v)
        # sorted and inside the range, the end terms peaking at its ends
        assert np.all(np.diff(p) > 0), p
        assert p[0] == lo and p[-1] == hi, (p, v.range)
        x = np.concatenate([np.linspace(lo, hi, 401), p])
        mu = degrees(v, x)
        if cc.free_triangles:
            for t in v.terms:
                a, b, c = t.params
                assert a < b < c
        else:  # a strong (Ruspini) partition: the degrees sum to one everywhere on the range
            np.testing.assert_allclose(mu.sum(axis=0), 1.0, atol=1e-12)
            np.testing.assert_allclose(mu[:, -len(p):], np.eye(len(p)), atol=1e-12)
    # the rule table: one rule per antecedent cell, or the template's rules
    if cc.tune == "breakpoints":
        assert rule_table_of(fis)[:, :2].tolist() == rule_table_of(tmpl)[:, :2].tolist()
    else:
        cells = [tuple(a.term for a in r.antecedents) for r in fis.rules]
        assert sorted(cells) == sorted(itertools.product(*[[t.name for t in v.terms]
                                                           for v in fis.inputs]))
        for r in fis.rules:
            assert r.consequents[0][1] in [t.name for t in out.terms]
    assert set(params) == expected_names(cc, fis)


def rule_table_of(fis) -> np.ndarray:
    return np.array([(json.dumps([(a.variable, a.term, a.negated) for a in r.antecedents]),
                      json.dumps(r.consequents), r.weight, r.connective) for r in fis.rules],
                    dtype=object)


@pytest.mark.parametrize("mode", sorted(CONFIGS))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_any_trial_builds_a_valid_system(mode, data):
    cc = CONFIGS[mode]
    space = ControllerSpace.from_config(cc)
    trial = DrawTrial(data)
    fis = space.build(trial)
    check_system(cc, fis, trial.params)
    # the stored parameters alone rebuild the same system (what export relies on)
    again = space.build(optuna.trial.FixedTrial(dict(trial.params)))
    assert again.to_dict() == fis.to_dict()


def test_random_trials_through_a_journal_rebuild_identically(tmp_path):
    """Parameters stored in (and reloaded from) a journal file rebuild the same systems."""
    from optuna.storages.journal import JournalFileBackend, JournalStorage

    spaces = [ControllerSpace.from_config(CONFIGS["both"]),
              ControllerSpace.from_config(controller(template=ATT, name="att",
                                                     partitions={"dom_att": (3, 5)},
                                                     window=(5, 9)))]
    path = str(tmp_path / "s.journal")
    study = optuna.create_study(storage=JournalStorage(JournalFileBackend(path)),
                                sampler=optuna.samplers.RandomSampler(seed=3))
    built = []
    for _ in range(60):
        trial = study.ask()
        systems = build_all(spaces, trial)
        for sp in spaces:
            own = {k: v for k, v in trial.params.items() if k.startswith(sp.config.name + ".")}
            check_system(sp.config, systems[sp.config.name], own)
        built.append({k: s.to_dict() for k, s in systems.items()})
        study.tell(trial, 1.0)
    again = optuna.load_study(study_name=study.study_name,
                              storage=JournalStorage(JournalFileBackend(path)))
    for t, ref in zip(again.trials, built):
        rebuilt = build_all(spaces, optuna.trial.FixedTrial(t.params, t.number))
        assert {k: s.to_dict() for k, s in rebuilt.items()} == ref
    # every structure got its own parameters: 3 x 3 and 5 x 7 rule tables never share a name
    structs = {k.split(".")[2] for t in again.trials for k in t.params if ".rule." in k}
    assert len(structs) > 4


def test_rules_mode_keeps_the_template_breakpoints():
    cc = controller(tune="rules", partitions={"dom_pos": (3, 5)})
    space = ControllerSpace.from_config(cc)
    tmpl = json.loads(GPS.read_text())
    for n in (3, 5):
        trial = optuna.trial.FixedTrial({"gps.n.dom_pos": n, **{
            f"gps.rule.{n}x3>4.{i}.{j}": (i + j) % 4 for i in range(n) for j in range(3)}})
        fis = space.build(trial)
        dom_pos, dom_vel = fis.inputs
        # the template's own triangles where the count is the template's ...
        assert [list(t.params) for t in dom_vel.terms] == \
            [t["params"] for t in tmpl["inputs"][1]["terms"]]
        assert [list(t.params) for t in fis.outputs[0].terms] == \
            [t["params"] for t in tmpl["outputs"][0]["terms"]]
        # ... evenly spread peaks for another count
        np.testing.assert_array_equal(peaks(dom_pos), np.linspace(-1.0, 1.0, n))
        assert not any(".gap." in k for k in trial.params)
        assert [r.consequents[0][1] for r in fis.rules] == [
            fis.outputs[0].terms[(i + j) % 4].name for i in range(n) for j in range(3)]


def test_rules_mode_keeps_template_terms_of_any_shape():
    """paper 002's ROR input ends with a trapezoid: kept as it is, not re-triangulated."""
    cc = controller(template=ROR_GNSS, tune="rules", partitions={}, free_triangles=True)
    space = ControllerSpace.from_config(cc)
    tmpl = json.loads(ROR_GNSS.read_text())
    params = {f"gps.rule.3>3.{i}": 2 - i for i in range(3)}
    fis = space.build(optuna.trial.FixedTrial(params))
    for var, ref in zip(fis.inputs + fis.outputs, tmpl["inputs"] + tmpl["outputs"]):
        assert [(t.name, t.mf, list(t.params)) for t in var.terms] == \
            [(t["name"], t["mf"], t["params"]) for t in ref["terms"]]
    assert [r.consequents[0][1] for r in fis.rules] == ["more1", "equal1", "less1"]


def test_breakpoints_mode_keeps_every_template_rule(tmp_path):
    """Including rules that are not full AND cells (an OR rule, a don't-care, a negation)."""
    doc = json.loads(GPS.read_text())
    doc["rules"] += [{"if": {"dom_pos": "NS"}, "then": {"alpha": "large"}, "weight": 0.3},
                     {"if": {"dom_pos": "PS", "dom_vel": {"not": "ZE"}},
                      "then": {"alpha": "small"}, "weight": 1.0, "connective": "or"}]
    tmpl = tmp_path / "template.json"
    tmpl.write_text(json.dumps(doc))
    cc = controller(template=tmpl, tune="breakpoints", partitions={})
    space = ControllerSpace.from_config(cc)
    rng = np.random.default_rng(0)
    params = {f"gps.gap.{v}.{n}.{k}": float(rng.uniform(0.05, 1.0))
              for v, n in (("dom_pos", 3), ("dom_vel", 3), ("alpha", 4)) for k in range(n - 1)}
    fis = space.build(optuna.trial.FixedTrial(params))
    ref = [(r["if"], r["then"], r["weight"], r.get("connective", "and")) for r in doc["rules"]]
    got = [({a.variable: {"not": a.term} if a.negated else a.term for a in r.antecedents},
            dict(r.consequents), r.weight, r.connective) for r in fis.rules]
    assert got == ref
    check_system(cc, fis, params)


def test_breakpoints_mode_rule_weights_replace_only_the_weights():
    cc = controller(tune="breakpoints", partitions={}, rule_weights=True)
    space = ControllerSpace.from_config(cc)
    trial = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1)).ask()
    fis = space.build(trial)
    tmpl = load_fis(GPS)
    assert [r.weight for r in fis.rules] == [trial.params[f"gps.weight.rule.{i}"]
                                             for i in range(len(tmpl.rules))]
    assert [(r.antecedents, r.consequents) for r in fis.rules] == \
        [(r.antecedents, r.consequents) for r in tmpl.rules]


def test_rule_weights_of_zero_make_the_output_its_default():
    """A sanity anchor used by the objective tests: no rule fires -> alpha = 1 (EKF)."""
    cc = controller(rule_weights=True)
    space = ControllerSpace.from_config(cc)
    trial = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=2)).ask()
    space.build(trial)
    params = {k: (0.0 if ".weight." in k else v) for k, v in trial.params.items()}
    fis = space.build(optuna.trial.FixedTrial(params))
    x = np.linspace(-1, 1, 7)
    y = fis.evaluate({"dom_pos": x[:, None], "dom_vel": x[None, :]})["alpha"]
    assert np.all(y == 1.0)
