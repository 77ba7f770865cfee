"""Rule files: lossless JSON round trip, schema, atomic writes, in-memory construction."""
import errno
import json
import os
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from fuzzynav.errors import OutputError
from fuzzynav.fuzzy import (Antecedent, FisError, FuzzySystem, Operators, Rule, Term,
                            Variable, load_fis, save_fis)
from fuzzynav.fuzzy.io import schema, to_dict
from tests.fuzzy.systems import ATT, GPS, ROR, RULES, random_mamdani
from tests.fuzzy.test_compiled import singleton_doc, sugeno_doc

RULE_FILES = sorted(RULES.glob("paper*.json"))


def _random_docs():
    rng = np.random.default_rng(99)
    for _ in range(10):
        doc = random_mamdani(rng, n_inputs=2, n_terms=3, n_out_terms=4,
                             out_shapes=("tri", "trap"), negate_prob=0.3, or_prob=0.3,
                             weight_prob=0.5, dont_care_prob=0.3)
        # floats that need all 17 digits
        doc["inputs"][0]["terms"][1]["params"][1] = float(rng.uniform(-0.5, 0.5))
        doc["outputs"][0]["default"] = 0.1 + 0.2
        doc["binding"] = {"adapter": "x", "nested": {"list": [1, 2.5, None, True, "s"]}}
        yield doc
    yield sugeno_doc(rng, 2, "linear")
    yield singleton_doc(rng, "mom")


@pytest.mark.parametrize("doc", list(_random_docs()))
def test_json_round_trip_is_lossless(doc, tmp_path):
    fis = load_fis(doc)
    path = tmp_path / "r.json"
    save_fis(fis, path)
    again = load_fis(path)
    assert again == fis
    assert again.to_dict() == fis.to_dict()
    assert json.loads(path.read_text()) == fis.to_dict()
    assert to_dict(load_fis(fis.to_dict())) == fis.to_dict()
    x = {n: np.linspace(-1, 1, 7) for n in fis.input_names}
    np.testing.assert_array_equal(again.evaluate(x)["y"], fis.evaluate(x)["y"])


@pytest.mark.parametrize("path", RULE_FILES, ids=lambda p: p.name)
def test_shipped_rule_files_are_canonical_and_schema_valid(path):
    doc = json.loads(path.read_text())
    jsonschema.Draft202012Validator(schema()).validate(doc)  # plain jsonschema
    assert load_fis(path).to_dict() == doc
    # hand-written files name their source; exported (tuned) ones their study and trial
    prov = doc["provenance"]
    assert doc["binding"]["adapter"] and (prov.get("source") or
                                          (prov.get("study") and "trial" in prov))


def test_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(schema())


def test_rule_files_of_the_papers_have_the_required_structure():
    gps = load_fis(GPS)
    assert gps.input_names == ("dom_pos", "dom_vel") and gps.output_names == ("alpha",)
    assert [t.name for t in gps.inputs[0].terms] == ["NS", "ZE", "PS"]
    assert [t.name for t in gps.outputs[0].terms] == ["zero", "small", "medium", "large"]
    table = {(r.antecedents[0].term, r.antecedents[1].term): r.consequents[0][1]
             for r in gps.rules}
    assert table == {("NS", "NS"): "medium", ("NS", "ZE"): "zero", ("NS", "PS"): "small",
                     ("ZE", "NS"): "small", ("ZE", "ZE"): "medium", ("ZE", "PS"): "large",
                     ("PS", "NS"): "medium", ("PS", "ZE"): "large", ("PS", "PS"): "zero"}
    assert gps.outputs[0].range[0] == 1.0 and gps.outputs[0].default == 1.0
    att = load_fis(ATT)
    assert [(r.antecedents[0].term, r.consequents[0][1]) for r in att.rules] == [
        ("NS", "XS"), ("ZE", "S"), ("PS", "M")]
    ror = load_fis(ROR)
    assert ror.binding["adapter"] == "r-scaling" and ror.binding["outputs"] == {"t": "r_scale"}
    eq = ror.outputs[0].terms[1]
    assert eq.name == "equal1" and eq.params[1] == 1.0


def _fail_with(err):
    def fail(*args, **kwargs):
        raise OSError(err, os.strerror(err))
    return fail


@pytest.mark.parametrize("target,err", [("replace", errno.ENOSPC), ("fsync", errno.ENOSPC),
                                        ("mkstemp", errno.EROFS)])
def test_save_is_atomic(tmp_path, monkeypatch, target, err):
    """A full disk (at the write or at the rename) or a read-only directory (simulated: the
    tests run as root, whom chmod does not stop): one OutputError naming the file, the old
    file unchanged, no temporary file left."""
    import tempfile

    fis = load_fis(ROR)
    path = tmp_path / "r.json"
    save_fis(fis, path)
    before = path.read_bytes()
    monkeypatch.setattr(tempfile if target == "mkstemp" else os, target, _fail_with(err))
    with pytest.raises(OutputError) as info:
        save_fis(load_fis(GPS), path)
    assert str(info.value) == (f"{path}: cannot write the rule file: {os.strerror(err)} "
                               "(nothing was changed)")
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["r.json"]  # no temporary file left behind


def test_load_from_dict_with_numpy_values():
    doc = json.loads(Path(ROR).read_text())
    doc["inputs"][0]["range"] = np.array([0.0, 3.0])
    doc["outputs"][0]["terms"][0]["params"] = np.array([0.5, 0.75, 1.0])
    assert load_fis(doc) == load_fis(ROR)


def test_programmatic_construction_and_its_errors():
    x = Variable("x", (0, 1), (Term("A", "tri", (0, 0, 1)), Term("B", "tri", (0, 1, 1))))
    y = Variable("y", (0, 1), (Term("lo", "tri", (0, 0.2, 0.4)),), default=0.5)
    rule = Rule((Antecedent("x", "A"),), (("y", "lo"),))
    fis = FuzzySystem("p", "mamdani", Operators(), (x,), (y,), (rule,))
    assert load_fis(fis.to_dict()) == fis
    assert hash(fis) == hash(load_fis(fis.to_dict()))
    with pytest.raises(FisError) as exc:
        FuzzySystem("p", "mamdani", Operators(), (x,), (y,),
                    (Rule((Antecedent("x", "C"),), (("y", "lo"),)),))
    assert exc.value.where == "rules[0].if.x" and exc.value.path is None
    with pytest.raises(FisError, match="range needs lo < hi"):
        Variable("x", (1, 0), x.terms)
    with pytest.raises(FisError, match="weight must be a number in"):
        Rule((Antecedent("x", "A"),), (("y", "lo"),), weight=2)
