"""Warm start of a fuzzy-supervisor study (issue 25): the first trial is the tuned parent.

The parent's score on the training run is computed independently of the study: the named
filter ``sage-husa-tuned`` reading the same tuned-parameter file, scored against the EKF by
the objective's scoring function.  The warm trial's system is a weighted average of equal
constants, which may differ from the constant by an ulp, so the scores are compared to
1e-9 relative, not bit for bit.
"""
import json

import pytest

from fuzzynav.errors import InputFileError
from tests.tuning.studies import RULES, TINY, study_doc, write_study

CONSTANTS = {"b": 0.95, "floor": 0.5, "cap": 20.0}


def _params(tmp_path, filters=None):
    path = tmp_path / "parent.json"
    path.write_text(json.dumps({"format": "fuzzynav-baselines", "version": 1,
                                "filters": filters or {"sage-husa-tuned": CONSTANTS}}))
    return path


def _controller(**changes):
    c = {"name": "gps", "template": str(RULES / "supervisor_sage_husa.json"),
         "partitions": {"ror": [3, 5], "b": [3, 5]}, "window": [3, 40],
         "output_low": [0.9, 0.984], "output_range": [0.985, 0.999],
         "types": ["mamdani", "sugeno"], "parent": "sage-husa-tuned@parent.json"}
    c.update(changes)
    return {k: v for k, v in c.items() if v is not None}


def _config(tmp_path, study=None, **changes):
    from fuzzynav.tuning.study_config import load_study_config

    _params(tmp_path)
    doc = study_doc(controllers=[_controller(**changes)],
                    objective={"filter": "fuzzy-sage-husa"},
                    train={"scenarios": [str(TINY)], "seeds": [0]},
                    study={"trials": 3, **(study or {})})
    return load_study_config(write_study(tmp_path, doc))


def test_the_first_trial_of_a_warm_study_scores_as_the_tuned_parent(tmp_path, sim_cache):
    from fuzzynav.experiment import run_on_log
    from fuzzynav.tuning.export import systems_of
    from fuzzynav.tuning.objective import Evaluator
    from fuzzynav.tuning.study_run import run_study

    cfg = _config(tmp_path)
    study = run_study(cfg, 3, 1, f"journal:{tmp_path / 's.journal'}", sim_cache,
                      progress=False)
    first = study.trials[0]
    assert first.user_attrs.get("warm_start") is True
    assert first.params["gps.type"] == "sugeno" and first.params["gps.out_lo"] == 0.95
    ev = Evaluator(cfg, sim_cache)
    parent = run_on_log(ev.log(str(TINY), 0), "sage-husa-tuned",
                        {"params": str(tmp_path / "parent.json")}).metrics
    want = ev.judge(parent, str(TINY), 0).score
    assert first.value == pytest.approx(want, rel=1e-9)
    # the default parent (b = 0.98, floor 0.1, no cap) scores otherwise: the check can fail
    plain = run_on_log(ev.log(str(TINY), 0), "sage-husa").metrics
    assert ev.judge(plain, str(TINY), 0).score != pytest.approx(want, rel=1e-6)
    # every candidate (and so the exported rule file) carries the tuned parent
    for t in study.trials:
        assert systems_of(cfg, t)["gps"].binding["parent"] == CONSTANTS
    # resumed, the study does not enqueue its first trial again
    again = run_study(cfg, 4, 1, f"journal:{tmp_path / 's.journal'}", sim_cache,
                      progress=False)
    assert sum(bool(t.user_attrs.get("warm_start")) for t in again.trials) == 1


def test_the_warm_trial_outputs_the_parents_constant_everywhere(tmp_path):
    """Checked on the built system (grid of the input range), at each output end."""
    from fuzzynav.tuning.space import ControllerSpace
    from fuzzynav.tuning.warm_start import PartialTrial, check_first_trial, first_trial

    for constants, key in (({"b": 0.93, "floor": 0.5, "cap": 20.0}, "gps.out_lo"),
                           ({"b": 0.99, "floor": 0.5, "cap": 20.0}, "gps.out_hi")):
        (tmp_path / "parent.json").unlink(missing_ok=True)
        cfg = _config(tmp_path)
        cc = cfg.controllers[0]
        cc = type(cc)(**{**cc.__dict__, "parent": (cc.parent[0], "", tuple(constants.items()))})
        space = ControllerSpace.from_config(cc)
        p = first_trial(space)
        assert p[key] == constants["b"]
        assert check_first_trial(space, p) <= 1e-12
        fis = space.build(PartialTrial(p))
        y = fis.evaluate({"ror": [0.0, 0.7, 1.0, 2.9]})
        assert all(abs(v - constants["b"]) < 1e-12 for v in y["b"])
        # a Mamdani system with the same consequents does not output the constant
        mam = space.build(PartialTrial({**p, "gps.type": "mamdani"}))
        ym = mam.evaluate({"ror": [0.0, 0.7, 1.0, 2.9]})["b"]
        assert max(abs(v - constants["b"]) for v in ym) > 1e-3


@pytest.mark.parametrize("changes, study, where", [
    (dict(types=["mamdani"]), None, "types"),
    (dict(tune="breakpoints", partitions=None), None, "tune"),
    (dict(output_low=[0.96, 0.97], output_range=[0.985, 0.999]), None, "output_low"),
    (dict(parent="vb-tuned@parent.json"), None, "parent"),
    (dict(parent="sage-husa-tuned@missing.json"), None, "parent"),
    (dict(template=str(RULES / "paper002_ror_gnss.json"), partitions=None,
          output_low=None, output_range=None), None, "parent"),
    ({}, {"sampler": "pso"}, "study.sampler"),
])
def test_a_warm_start_the_space_cannot_hold_is_refused(tmp_path, changes, study, where):
    with pytest.raises(InputFileError) as err:
        _config(tmp_path, study, **changes)
    assert err.value.where.endswith(where), err.value


def test_a_parent_missing_from_the_params_file_is_refused(tmp_path):
    _params(tmp_path, {"huber-tuned": {"gamma": 1.5}})
    from fuzzynav.tuning.study_config import load_study_config

    doc = study_doc(controllers=[_controller()], objective={"filter": "fuzzy-sage-husa"})
    with pytest.raises(InputFileError, match="tunes no 'sage-husa-tuned'"):
        load_study_config(write_study(tmp_path, doc))
