"""MATLAB .fis files: reading MATLAB's example, round trips of Mamdani and Sugeno systems."""
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.fuzzy import FisError, load_fis, read_matlab_fis, write_matlab_fis
from fuzzynav.fuzzy.fis_matlab import dropped_fields, matlab_text
from tests.fuzzy.systems import GPS, TIPPER, random_mamdani
from tests.fuzzy.test_compiled import sugeno_doc



def test_reads_matlab_tipper():
    fis = read_matlab_fis(TIPPER)
    assert fis.type == "mamdani" and fis.input_names == ("service", "food")
    assert fis.inputs[0].terms[1].mf == "gauss" and fis.inputs[0].terms[1].params == (1.5, 5.0)
    r0, r1 = fis.rules[0], fis.rules[1]
    assert r0.connective == "or" and [a.term for a in r0.antecedents] == ["poor", "rancid"]
    assert [a.variable for a in r1.antecedents] == ["service"]  # 0 = don't care
    assert load_fis(TIPPER) == fis  # load_fis dispatches on the extension


def _mamdani_docs():
    rng = np.random.default_rng(4)
    for k in range(6):
        yield random_mamdani(rng, n_inputs=2, n_terms=3, n_out_terms=4,
                             out_shapes=("tri", "trap"), negate_prob=0.3, or_prob=0.3,
                             weight_prob=0.5, dont_care_prob=0.3,
                             ops={"aggregation": ("max", "sum", "probor")[k % 3],
                                  "defuzzifier": ("centroid", "bisector", "mom")[k % 3]})


@pytest.mark.parametrize("doc", list(_mamdani_docs()) + [
    sugeno_doc(np.random.default_rng(1), 2, "linear"),
    sugeno_doc(np.random.default_rng(2), 3, "constant")])
def test_fis_round_trip(doc, tmp_path):
    doc["inputs"][0]["terms"][0]["params"][0] *= 1.0 + 2.0**-50  # needs 17 digits
    fis = load_fis(doc)
    path = tmp_path / "x.fis"
    assert write_matlab_fis(fis, path) == []
    again = read_matlab_fis(path)
    assert again == fis
    write_matlab_fis(again, tmp_path / "y.fis")
    assert (tmp_path / "y.fis").read_text() == path.read_text()


def test_fis_text_is_matlab_style():
    text = Path(TIPPER).read_text()
    ours = matlab_text(read_matlab_fis(TIPPER))
    for line in ("MF1='poor':'gaussmf',[1.5 0]", "Range=[0 30]", "1 1, 1 (1) : 2",
                 "2 0, 2 (1) : 1", "NumRules=3", "DefuzzMethod='centroid'"):
        assert line in ours and line in text


def test_what_fis_cannot_hold_is_reported_or_refused(tmp_path):
    gps = load_fis(GPS)
    dropped = write_matlab_fis(gps, tmp_path / "g.fis")
    assert dropped == dropped_fields(gps) == ["outputs.alpha.default", "binding", "provenance"]
    back = read_matlab_fis(tmp_path / "g.fis")
    assert back.rules == gps.rules and back.outputs[0].default is None
    doc = random_mamdani(np.random.default_rng(0), n_inputs=1, n_terms=3, n_out_terms=2)
    doc["outputs"][0]["terms"] = [{"name": "a", "mf": "singleton", "params": [0.3]}]
    doc["rules"] = [{"if": {"x0": "T0"}, "then": {"y": "a"}}]
    with pytest.raises(FisError, match="no MATLAB .fis equivalent"):
        write_matlab_fis(load_fis(doc), tmp_path / "s.fis")
