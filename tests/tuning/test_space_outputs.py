"""Study spaces over several outputs (R step and Q level), Mamdani or Sugeno systems."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import optuna
import pytest
import skfuzzy

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.rq_scaling import FuzzyRQScaling
from fuzzynav.fuzzy import load_fis
from fuzzynav.fuzzy.io import save_fis
from fuzzynav.fuzzy.kernels import eval_compiled_batch
from fuzzynav.tuning.study_config import load_study_config, study_config_from_dict
from fuzzynav.tuning.space import ControllerSpace

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "studies" / "paper000_fair_ctl.toml"
INPUTS = ("ror", "nis", "trend", "speed", "rate", "force")

optuna.logging.set_verbosity(optuna.logging.ERROR)


def _build(kind, seed=3, **counts):
    space = ControllerSpace.from_config(load_study_config(STUDY).controllers[0])
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=seed))
    study.enqueue_trial({"gps.type": kind} | {f"gps.n.{k}": v for k, v in counts.items()})
    return space.build(study.ask())


def _at(ror, **over):
    """Inputs with ``ror`` varying and the others at mid-range values."""
    x = {"ror": np.asarray(ror, float), "nis": 1.0, "trend": 0.0, "speed": 10.0, "rate": 2.0,
         "force": 0.0}
    return {k: np.broadcast_to(np.asarray(over.get(k, v), float), np.shape(ror))
            for k, v in x.items()}


def test_every_rule_drives_both_outputs_and_q_keeps_its_range():
    fis = _build("mamdani", ror=3, nis=1, trend=1, speed=2, rate=1, force=1, t=5, q=3)
    assert fis.output_names == ("t", "q")
    assert len(fis.rules) == 3 * 2  # ror x speed cells; the other inputs are off
    assert all({o for o, _ in r.consequents} == {"t", "q"} for r in fis.rules)
    assert fis.outputs[1].range == (0.5, 4.0) and len(fis.outputs[1].terms) == 3
    FuzzyRQScaling(fis, "built")  # binds to the rq-scaling policy, both outputs


def test_a_sugeno_system_is_the_weighted_average_of_its_rule_constants():
    fis = _build("sugeno", ror=5, nis=1, trend=1, speed=1, rate=1, force=1, t=3, q=2)
    assert fis.type == "sugeno" and fis.operators.defuzzifier == "wtaver"
    ror = np.linspace(0.0, 3.0, 13)
    got = fis.evaluate(_at(ror))
    # only ror is on: the firing strengths are its (strong triangular) memberships
    assert all(t.mf == "tri" for t in fis.inputs[0].terms)
    mu = np.column_stack([skfuzzy.trimf(ror, list(t.params)) for t in fis.inputs[0].terms])
    for out in fis.outputs:
        const = {t.name: t.params[0] for t in out.terms}
        c = np.array([const[dict(r.consequents)[out.name]] for r in fis.rules])
        np.testing.assert_allclose(got[out.name], mu @ c / mu.sum(axis=1), rtol=1e-12)


@pytest.mark.parametrize("kind", ["mamdani", "sugeno"])
def test_built_systems_compile_to_what_the_exact_path_gives(kind, tmp_path):
    fis = _build(kind, seed=7, ror=5, nis=3, trend=2, speed=2, rate=2, force=1, t=5, q=3)
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(*v.range, 50) for v in fis.inputs])
    cf = fis.compile()
    Y, _ = eval_compiled_batch(cf.fparams, cf.iparams, X)
    ref = fis.evaluate(dict(zip(fis.input_names, X.T)))
    for j, name in enumerate(fis.output_names):
        np.testing.assert_allclose(Y[:, j], ref[name], rtol=1e-9, atol=1e-12)
    save_fis(fis, tmp_path / "f.json")  # the rule-file schema holds it: it reads back equal
    back = load_fis(tmp_path / "f.json").evaluate(dict(zip(fis.input_names, X.T)))
    for name in fis.output_names:
        np.testing.assert_allclose(back[name], ref[name], rtol=1e-12)


def test_the_type_is_a_trial_parameter_only_when_there_is_a_choice():
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    cc = load_study_config(STUDY).controllers[0]
    trial = study.ask()
    ControllerSpace.from_config(cc).build(trial)
    assert trial.params["gps.type"] in ("mamdani", "sugeno")
    trial = study.ask()
    fis = ControllerSpace.from_config(replace(cc, types=("mamdani",))).build(trial)
    assert "gps.type" not in trial.params and fis.type == "mamdani"


def test_types_must_name_system_types(tmp_path):
    doc = {"name": "s", "study": {"trials": 1}, "train": {"scenarios": ["paper000"],
           "seeds": [0]}, "test": {"scenarios": ["paper000"], "seeds": [1]},
           "controllers": [{"name": "gps",
                            "template": str(ROOT / "rules" / "paper000_rq_select_gnss.json"),
                            "types": ["mamdani", "tsk2"]}]}
    with pytest.raises(InputFileError, match=r"controllers.*types.*mamdani, sugeno"):
        study_config_from_dict(doc, tmp_path / "s.toml")


def test_a_tuned_sugeno_system_runs_in_the_compiled_loop_as_it_evaluates():
    from fuzzynav.filters.runner import run_filter
    from tests.filters.simple_data import CONFIG
    from tests.filters.test_context_inputs import _turntable

    fis = _build("sugeno", ror=5, nis=1, trend=1, speed=1, rate=1, force=1, t=3, q=2)
    imu, gnss, init, _ = _turntable(0.05, seconds=40.0)
    res = run_filter(imu, {"gnss": gnss}, init, CONFIG,
                     adapters={"gnss": FuzzyRQScaling(fis, "built")})
    ev = res.events["gnss"]
    col = {n: ev.diag[:, ev.diag_names.index(n)] for n in ("t", "q_scale", "ror")}
    ref = fis.evaluate(_at(col["ror"]))  # the only input switched on is ror
    np.testing.assert_allclose(col["t"], ref["t"], rtol=1e-9)
    lo, hi = fis.outputs[1].range
    np.testing.assert_allclose(col["q_scale"], ref["q"], rtol=1e-9)  # the level, not clamped
    assert lo <= col["q_scale"].min() and col["q_scale"].max() <= hi
