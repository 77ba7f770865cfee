"""``fuzzynav fis``: surface, check, convert — output and exit codes."""
import csv
import io
import json
import re

import numpy as np
import pytest

from fuzzynav.cli import main
from fuzzynav.fuzzy import load_fis
from tests.floats import ULP_RTOL
from tests.fuzzy.systems import DATA, GPS, ROR



def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_surface_table_matches_evaluate(capsys):
    code, out, err = run(capsys, "fis", "surface", GPS, "--grid", "5")
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].startswith("paper000-gps-sins")
    assert "rows: dom_pos" in out and "columns: dom_vel" in out
    rows = [ln.split() for ln in lines if re.match(r"^-?\d", ln)]
    assert len(rows) == 5 and all(len(r) == 6 for r in rows)
    g = np.linspace(-1, 1, 5)
    ref = load_fis(GPS).evaluate({"dom_pos": g[:, None], "dom_vel": g[None, :]})["alpha"]
    np.testing.assert_allclose(np.array([[float(v) for v in r[1:]] for r in rows]), ref,
                               atol=5e-5)
    assert [float(r[0]) for r in rows] == list(g)


def test_surface_csv_is_complete_and_exact(capsys):
    code, out, _ = run(capsys, "fis", "surface", GPS, "--grid", "4", "--csv")
    assert code == 0
    table = list(csv.reader(io.StringIO(out)))
    assert table[0] == ["dom_pos", "dom_vel", "alpha"] and len(table) == 17
    fis = load_fis(GPS)
    for a, b, y in table[1:]:
        # printed in full (a rounded print would be off by far more than an ulp); the CLI
        # evaluates the whole grid as one batch, here one sample at a time: to rounding
        one = fis.evaluate({"dom_pos": float(a), "dom_vel": float(b)})["alpha"]
        assert float(y) == pytest.approx(one, rel=ULP_RTOL, abs=0.0)


def test_surface_of_a_one_input_system(capsys):
    code, out, _ = run(capsys, "fis", "surface", ROR, "--grid", "7")
    assert code == 0
    rows = [ln.split() for ln in out.splitlines() if re.match(r"^\d", ln)]
    assert [r[0] for r in rows] == ["0", "0.5", "1", "1.5", "2", "2.5", "3"]
    assert rows[2][1] == "1.000"


def test_check_prints_a_summary(capsys):
    code, out, _ = run(capsys, "fis", "check", GPS)
    assert code == 0
    assert "OK" in out.splitlines()[0]
    assert "rules (9)" in out and "exponential-weighting" in out
    assert re.search(r"NS\s+medium\s+zero\s+small", out)  # the rule table of the paper
    assert "advisories: none" in out
    assert len(out.splitlines()) <= 24


def test_convert_round_trip(capsys, tmp_path):
    fis_path = tmp_path / "g.fis"
    code, out, err = run(capsys, "fis", "convert", GPS, str(fis_path))
    assert code == 0 and "MATLAB .fis" in out and "cannot hold" in err
    back = tmp_path / "g.json"
    assert run(capsys, "fis", "convert", str(fis_path), str(back))[0] == 0
    assert load_fis(back).rules == load_fis(GPS).rules


@pytest.mark.parametrize("argv,fragment", [
    (["fis", "surface", "nope.json"], "nope.json: no such rule file"),
    (["fis", "check", str(DATA / "bad_fis" / "unsorted_params.json")],
     "$.inputs[0].terms[1].params: parameters must satisfy a <= b <= c"),
    (["fis", "surface", GPS, "--output", "beta"], "--output beta: no such output"),
    (["fis", "surface", GPS, "--at", "zzz=1"], "--at zzz: no such input"),
    (["fis", "convert", GPS, "out.txt"], "unknown rule-file extension"),
])
def test_errors_are_one_line_with_exit_code_2(capsys, argv, fragment):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and fragment in err and err.startswith("fuzzynav: error: ")


def test_bad_grid_is_an_argument_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["fis", "surface", GPS, "--grid", "1"])
    assert exc.value.code == 2
    assert "grid size must be 2..1001" in capsys.readouterr().err


def test_check_lists_advisories(capsys, tmp_path):
    doc = json.loads(open(GPS).read())
    doc["inputs"][0]["terms"][1]["params"] = [-1.0, 0.0, 0.2]  # gap on (0.2, 0.5)
    doc["inputs"][0]["terms"][2]["params"] = [0.5, 1.0, 2.0]
    doc["rules"].append({"if": {"dom_pos": "NS", "dom_vel": "NS"}, "then": {"alpha": "zero"}})
    path = tmp_path / "a.json"
    path.write_text(json.dumps(doc))
    code, out, _ = run(capsys, "fis", "check", str(path))
    assert code == 0
    assert "no term is active" in out and "rules 0 and 9" in out
