"""A study space selects inputs: a partition count of 1 switches an input off."""
from pathlib import Path

import numpy as np
import optuna
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.tuning.study_config import load_study_config, study_config_from_dict
from fuzzynav.tuning.space import ControllerSpace

ROOT = Path(__file__).resolve().parents[2]


def _space():
    cfg = load_study_config(ROOT / "studies" / "paper000_select.toml")
    return ControllerSpace.from_config(cfg.controllers[0])


def _build(space, **counts):
    """A system with the given partition counts, the other parameters drawn at random."""
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=3))
    study.enqueue_trial({f"gps.n.{k}": v for k, v in counts.items()})
    return space.build(study.ask())


def test_an_input_with_one_term_does_not_change_the_output():
    fis = _build(_space(), ror=3, nis=3, trend=1, t=3)
    assert [len(v.terms) for v in fis.inputs] == [3, 3, 1]
    ror, nis = np.full(5, 1.4), np.full(5, 0.8)
    out = fis.evaluate({"ror": ror, "nis": nis, "trend": np.linspace(-1.0, 1.0, 5)})["t"]
    assert np.ptp(out) == pytest.approx(0.0, abs=1e-12)
    # ...while an input that is on does change it somewhere on its range
    out = fis.evaluate({"ror": np.linspace(0.0, 3.0, 7), "nis": np.full(7, 0.8),
                        "trend": np.zeros(7)})["t"]
    assert np.ptp(out) > 0.0


def test_an_output_cannot_be_switched_off(tmp_path):
    doc = {"name": "s", "study": {"trials": 1}, "train": {"scenarios": ["paper000"],
           "seeds": [0]}, "test": {"scenarios": ["paper000"], "seeds": [1]},
           "controllers": [{"name": "gps",
                            "template": str(ROOT / "rules" / "paper000_select_gnss.json"),
                            "partitions": {"t": [1, 3]}}]}
    with pytest.raises(InputFileError, match=r"partitions\.t.*at least 2 terms"):
        study_config_from_dict(doc, tmp_path / "s.toml")
