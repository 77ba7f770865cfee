"""Study configs: every shipped example loads; every mistake is one error naming file and key."""
from __future__ import annotations

import json
import shutil
import sys

import pytest

from fuzzynav.errors import DataMissingError, FuzzynavError, InputFileError
from fuzzynav.tuning.study_config import load_study_config
from tests.tuning.studies import (ATT_CONTROLLER, BASE, GPS, ROOT, STUDIES, TINY, study_doc,
                                  write_study)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# baseline studies ([baselines], no controllers; paper 004's APSO among them) are checked in
# tests/tuning/test_baselines.py and tests/tuning/test_apso.py
EXAMPLES = sorted(p for p in STUDIES.glob("*.toml") if "[baselines]" not in p.read_text())


def _ctrl(**kw):
    return [dict(BASE["controllers"][0], **kw)]


def _expected_runs(doc: dict) -> list:
    """Scenarios x seeds, then each recording's sessions x recording seeds."""
    from fuzzynav.realdata.dataspec import expand, parse_recording_spec

    runs = [(sc, sd) for sc in doc.get("scenarios", []) for sd in doc.get("seeds", [])]
    recs = [str(s) for r in doc.get("recordings", []) for s in expand(parse_recording_spec(r))]
    return runs + [(r, sd) for r in recs for sd in doc.get("recording_seeds", [0])]


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_configs_load_and_say_what_the_file_says(path, tmp_path, monkeypatch):
    doc = tomllib.loads(path.read_text())
    # recordings: loading a config only checks that their directories exist
    from fuzzynav.realdata.dataspec import DATA_DIR_ENV, parse_recording_spec

    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))
    for key in ("train", "test"):
        for spec in doc[key].get("recordings", []):
            (tmp_path / parse_recording_spec(spec).directory).mkdir(parents=True, exist_ok=True)
    cfg = load_study_config(path)
    st = doc["study"]
    assert cfg.name == doc["name"]
    assert (cfg.sampler, cfg.seed, cfg.trials) == (st["sampler"], st["seed"], st["trials"])
    assert cfg.pruner == st.get("pruner", "wilcoxon")
    assert cfg.multi_objective == (st.get("objective", "single") == "multi")
    for key, runs in (("train", cfg.train), ("test", cfg.test)):
        assert list(runs) == _expected_runs(doc[key])
    assert cfg.compare == tuple(doc["test"].get("compare", ["ekf", "fakf"]))
    assert [c.name for c in cfg.controllers] == [c["name"] for c in doc["controllers"]]
    for c, raw in zip(cfg.controllers, doc["controllers"]):
        assert c.template == (path.parent / raw["template"]) and c.template.is_file()
        assert {k: list(v) for k, v in c.partitions.items()} == {
            k: sorted(v) for k, v in raw.get("partitions", {}).items()}
        assert c.window == (tuple(raw["window"]) if "window" in raw else None)
    # the default storage is a journal file next to the config
    assert cfg.storage_url == f"journal:{path.parent / (cfg.name + '.journal')}"


def test_defaults_and_derived_values(tmp_path):
    doc = study_doc(study={"sampler": "tpe"})
    del doc["study"]["pruner"], doc["study"]["stale_after_s"], doc["test"]["compare"]
    cfg = load_study_config(write_study(tmp_path, doc))
    assert cfg.pruner == "wilcoxon" and cfg.stale_after_s == 300.0
    assert cfg.weights == {"pos": 1.0, "vel": 1.0, "att": 1.0} and cfg.baseline == "ekf"
    assert cfg.compare == ("ekf", "fakf") and cfg.directions == ["minimize"]
    assert cfg.filter == "fakf"  # the candidates run in the fuzzy EKF unless told otherwise
    assert cfg.train == ((str(TINY), 0), (str(TINY), 1))
    multi = load_study_config(write_study(tmp_path, study_doc(study={"objective": "multi"})))
    assert multi.directions == ["minimize"] * 3


def test_relative_template_and_scenario_files_are_next_to_the_config(tmp_path, monkeypatch):
    shutil.copy(TINY, tmp_path / "short.toml")
    (tmp_path / "rules").mkdir()
    shutil.copy(GPS, tmp_path / "rules" / "g.json")
    path = write_study(tmp_path, train={"scenarios": ["short.toml"]},
                       controllers=_ctrl(template="rules/g.json"))
    monkeypatch.chdir(ROOT)  # anywhere but the config's directory
    cfg = load_study_config(path)
    assert cfg.train[0] == (str(tmp_path / "short.toml"), 0)
    assert cfg.controllers[0].template == tmp_path / "rules" / "g.json"


BAD = [
    # (changes to the base document, the key named, a fragment of the message)
    (dict(colour="red"), "colour", "unknown key"),
    (dict(study={"samplr": "tpe"}), "study.samplr", "unknown key"),
    (dict(study={"sampler": "bayes"}), "study.sampler", "must be one of"),
    (dict(study={"pruner": "hyperband"}), "study.pruner", "must be one of"),
    (dict(study={"trials": 0}), "study.trials", "must lie in"),
    (dict(study={"stale_after_s": 0.0}), "study.stale_after_s", "must lie in"),
    (dict(study={"objective": "multi", "sampler": "pso"}), "study.sampler", "single-objective"),
    (dict(study={"sampler": "pso", "pso": {"inertia": [0.4, 0.9]}}), "study.pso.inertia",
     "start weight"),
    (dict(study={"sampler": "pso", "pso": {"particles": 1}}), "study.pso.particles",
     "must lie in"),
    (dict(objective={"weights": {"pos": 0.0, "vel": 0.0, "att": 0.0}}), "objective.weights",
     "at least one weight"),
    (dict(objective={"weights": {"pos": 1.0, "speed": 1.0}}), "objective.weights.speed",
     "unknown key"),
    (dict(study={"objective": "multi"}, objective={"weights": {"pos": 1.0, "hdg": 1.0}}),
     "objective.weights.hdg", "pos, vel and att only"),
    (dict(objective={"baseline": "ekff"}), "objective.baseline", "unknown filter 'ekff'"),
    (dict(train={"seeds": []}), "train.seeds", "non-empty array"),
    (dict(train={"seeds": [-1]}), "train.seeds", "non-negative"),
    (dict(train={"scenarios": []}), "train.scenarios", "non-empty array"),
    (dict(train={"scenarios": ["paper999"]}), "train.scenarios[0]", "unknown scenario"),
    (dict(test={"scenarios": ["paper000", "nowhere/x.toml"]}), "test.scenarios[1]",
     "not found"),
    (dict(train={"seed": [1]}), "train.seed", "unknown key"),
    (dict(test={"compare": ["ekf", "sage_husa"]}), "test.compare[1]", "unknown filter"),
    (dict(test={"compare": "ekf"}), "test.compare", "array of filter names"),
    (dict(controllers=[]), "controllers", "at least one"),
    (dict(controllers=_ctrl() * 2), "controllers", "unique"),
    (dict(controllers=_ctrl(template="missing.json")), "controllers[0].template", "not found"),
    (dict(controllers=_ctrl(tune="all")), "controllers[0].tune", "must be one of"),
    (dict(controllers=_ctrl(partitions={"dom_pos": [3, 10]})), "controllers[0].partitions.dom_pos",
     "2..9"),
    (dict(controllers=_ctrl(partitions={"dom_att": [3]})), "controllers[0].partitions.dom_att",
     "has no variable 'dom_att'"),
    (dict(controllers=_ctrl(tune="breakpoints")), "controllers[0].partitions.dom_pos",
     "tune = 'breakpoints'"),
    (dict(controllers=_ctrl(window=[0, 10])), "controllers[0].window", "integer epoch counts"),
    (dict(controllers=_ctrl(window=[5.5, 10])), "controllers[0].window", "integer epoch counts"),
    (dict(controllers=_ctrl(window=[10, 5])), "controllers[0].window", "lo < hi"),
    (dict(controllers=_ctrl(output_range=[1.2])), "controllers[0].output_range", "2 numbers"),
    (dict(controllers=_ctrl(output_low=[0.9, 1.05])), "controllers[0].output_low",
     "below output_range"),
    (dict(controllers=_ctrl(output_range=None, output_low=[0.9, 1.2])),
     "controllers[0].output_low", "below the template's upper end"),
    (dict(controllers=_ctrl(output_range=[0.9, 1.3])), "controllers[0].output_range",
     "above the template's lower end"),
    (dict(controllers=_ctrl(free_triangles="yes")), "controllers[0].free_triangles",
     "true or false"),
    (dict(controllers=[dict(_ctrl()[0], bindng={})]), "controllers[0].bindng", "unknown key"),
    (dict(name="../escape"), "name", "names the journal file"),
    (dict(objective={"filter": "ekf"}), "objective.filter", "does not"),
    (dict(objective={"filter": "fakf2"}), "objective.filter", "unknown filter"),
]


@pytest.mark.parametrize("changes,key,fragment", BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_every_mistake_is_one_error_naming_the_file_and_key(tmp_path, changes, key, fragment):
    doc = study_doc(**changes)
    for c in doc.get("controllers", []):
        for k in [k for k, v in c.items() if v is None]:
            del c[k]
    path = write_study(tmp_path, doc, file_name="bad.toml")
    with pytest.raises(InputFileError) as err:
        load_study_config(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: {key}: "), msg
    assert fragment in msg, msg
    assert "\n" not in msg


def test_missing_tables_are_named(tmp_path):
    for table in ("study", "train", "test"):
        doc = study_doc()
        del doc[table]
        path = write_study(tmp_path, doc, file_name="bad.toml")
        with pytest.raises(InputFileError, match=rf"^{path}: {table}: missing required key"):
            load_study_config(path)


def test_a_misspelt_table_is_named_beside_the_one_missing(tmp_path):
    doc = study_doc()
    doc["trian"] = doc.pop("train")
    path = write_study(tmp_path, doc, file_name="bad.toml")
    with pytest.raises(InputFileError, match=rf"^{path}: train: missing required key "
                                             r"\(is 'trian' a misspelling of it\?\)"):
        load_study_config(path)


def test_a_broken_template_is_reported_by_its_own_file_and_json_path(tmp_path):
    bad = ROOT / "tests" / "data" / "bad_fis" / "unsorted_params.json"
    path = write_study(tmp_path, controllers=[dict(ATT_CONTROLLER, template=str(bad))])
    with pytest.raises(InputFileError) as err:
        load_study_config(path)
    assert str(err.value).startswith(f"{bad}: $.inputs[0].terms[1].params")


def test_a_sugeno_template_cannot_be_tuned(tmp_path):
    doc = json.loads(GPS.read_text())
    doc["type"] = "sugeno"
    doc["operators"] = {"and": "min", "or": "max", "defuzzifier": "wtaver"}
    doc["outputs"][0]["terms"] = [{"name": t["name"], "mf": "constant", "params": [t["params"][1]]}
                                  for t in doc["outputs"][0]["terms"]]
    (tmp_path / "sugeno.json").write_text(json.dumps(doc))
    path = write_study(tmp_path, controllers=_ctrl(template="sugeno.json"))
    with pytest.raises(InputFileError, match=r"controllers\[0\]\.template: .*Mamdani"):
        load_study_config(path)


def test_cmaes_without_its_package_is_named(tmp_path, monkeypatch):
    import importlib.util

    find = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "cmaes" else find(name, *a))
    path = write_study(tmp_path, study={"sampler": "cmaes"})
    with pytest.raises(InputFileError, match=rf"^{path}: study.sampler: .*pip install cmaes"):
        load_study_config(path)


def test_file_level_problems(tmp_path):
    with pytest.raises(DataMissingError, match="nope.toml: study file not found"):
        load_study_config(tmp_path / "nope.toml")
    bad = tmp_path / "broken.toml"
    bad.write_text("name = 'x'\n[study\n")
    with pytest.raises(InputFileError, match=rf"^{bad}: invalid TOML"):
        load_study_config(bad)
    latin = tmp_path / "latin.toml"
    latin.write_bytes("name = 'caf\xe9'\n".encode("latin-1"))
    with pytest.raises(FuzzynavError, match=rf"^{latin}: not UTF-8"):
        load_study_config(latin)
