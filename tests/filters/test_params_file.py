"""Tuned-parameter files: one reader checks every filter, key and range (one line each)."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from fuzzynav.cli import main
from fuzzynav.errors import InputFileError
from fuzzynav.filters.baselines import read_params
from fuzzynav.filters.params_file import PARAMETERS, read_params_file

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "studies" / "paper000_baselines.json"
APSO = ROOT / "studies" / "paper004_apso_rev.json"


def _doc():
    return json.loads(SHIPPED.read_text())


def _with(edit):
    doc = copy.deepcopy(_doc())
    edit(doc["filters"])
    return doc


def _set(name, key, value):
    def edit(f):
        f[name][key] = value
    return edit


BAD = [
    ("unknown key", _set("ekf-tuned", "r_bogus", 2.0), "$.filters.ekf-tuned.r_bogus",
     "unknown parameter of ekf-tuned"),
    ("sage-husa b above 1", _set("sage-husa-tuned", "b", 1.5), "$.filters.sage-husa-tuned.b",
     "must be a number in (0, 1)"),
    ("vb fractional iterations", _set("vb-tuned", "iterations", 2.5),
     "$.filters.vb-tuned.iterations", "must be an integer in [1, 100]"),
    ("an absurd R factor", _set("ekf-tuned", "r_pos", 1e300), "$.filters.ekf-tuned.r_pos",
     "must be a number in [1e-06, 1e+06]"),
    ("a zero factor", _set("ekf-tuned", "q_att", 0.0), "$.filters.ekf-tuned.q_att", "[1e-06"),
    ("a string", _set("huber-tuned", "gamma", "1.3"), "$.filters.huber-tuned.gamma",
     "got '1.3'"),
    ("a boolean", _set("huber-tuned", "gamma", True), "$.filters.huber-tuned.gamma",
     "got True"),
    ("empty parameters", lambda f: f.update({"sage-husa-tuned": {}}),
     "$.filters.sage-husa-tuned", "plain EKF"),
    ("a missing key", lambda f: f["vb-tuned"].pop("rho"), "$.filters.vb-tuned", "misses rho"),
    ("cap below floor", _set("sage-husa-tuned", "cap", 0.5), "$.filters.sage-husa-tuned.cap",
     "must exceed floor"),
    ("strong tracking beta below 1", _set("strong-tracking-tuned", "beta", 0.5),
     "$.filters.strong-tracking-tuned.beta", "[1, 1000]"),
    ("an unknown filter", lambda f: f.update({"kalman-magic": {"x": 1.0}}),
     "$.filters.kalman-magic", "not a tuned filter"),
    ("parameters not an object", lambda f: f.update({"huber-tuned": [1.3]}),
     "$.filters.huber-tuned", "must be an object"),
]


@pytest.mark.parametrize("label, edit, where, phrase", BAD, ids=[b[0] for b in BAD])
def test_a_bad_parameter_file_is_one_line_naming_the_key(tmp_path, label, edit, where, phrase):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(_with(edit)))
    with pytest.raises(InputFileError) as exc:
        read_params_file(path)
    msg = str(exc.value)
    assert msg.startswith(f"{path}: {where}:") and phrase in msg and "\n" not in msg


TOP = [
    ("a later version", lambda d: d.update(version=7), "$.version", "unsupported version 7"),
    ("a version as text", lambda d: d.update(version="1"), "$.version",
     "unsupported version '1'"),
    ("an unknown key", lambda d: d.update(extra_top=1), "$.extra_top",
     "unknown key of a tuned-parameter file"),
]


@pytest.mark.parametrize("label, edit, where, phrase", TOP, ids=[t[0] for t in TOP])
def test_the_file_itself_is_checked_too(tmp_path, label, edit, where, phrase):
    doc = _doc()
    edit(doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputFileError) as exc:
        read_params_file(path)
    msg = str(exc.value)
    assert msg.startswith(f"{path}: {where}:") and phrase in msg and "\n" not in msg


def test_a_hand_written_file_may_leave_the_version_out(tmp_path):
    doc = _doc()
    del doc["version"]
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(doc))
    assert read_params_file(path) == read_params_file(SHIPPED)


def test_the_shipped_files_read_back_unchanged():
    assert read_params(SHIPPED)["filters"] == _doc()["filters"]
    assert read_params(APSO)["filters"] == json.loads(APSO.read_text())["filters"]


def test_every_tuned_filter_registered_is_declared():
    from fuzzynav.filters.named import list_filters

    takers = {f.name for f in list_filters() if f.takes_params}
    assert takers <= set(PARAMETERS), takers - set(PARAMETERS)


def test_an_older_apso_file_with_multipliers_is_refused(tmp_path):
    path = tmp_path / "apso.json"
    path.write_text(json.dumps({"multipliers": {}}))
    with pytest.raises(InputFileError, match=r"\$\.multipliers: an old APSO result file"):
        read_params_file(path)


@pytest.mark.parametrize("spec, phrase", [
    ("ekf-tuned@", "no file after '@'"),
    ("fakf@+", "no file after '@'"),
    ("sage-husa-tuned@{bad}", "$.filters.sage-husa-tuned.b: must be a number in (0, 1)"),
])
def test_the_cli_refuses_in_one_line(tmp_path, capsys, spec, phrase):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(_with(_set("sage-husa-tuned", "b", 1.5))))
    code = main(["run", "paper000", "--filter", spec.format(bad=bad), "--cache",
                 str(tmp_path / "cache")])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and phrase in err and err.count("\n") == 1, err


def test_the_one_finder_finds_a_bare_name_in_studies_and_refuses_a_directory(tmp_path,
                                                                              monkeypatch):
    from fuzzynav.errors import DataMissingError
    from fuzzynav.filters.catalog import find_params_file, find_rule_file

    monkeypatch.chdir(tmp_path)  # not the checkout: the bare name comes from its studies/
    assert find_params_file(SHIPPED.name).resolve() == SHIPPED.resolve()
    (tmp_path / "studies").mkdir()
    mine = tmp_path / "studies" / SHIPPED.name
    mine.write_text(SHIPPED.read_text())
    assert find_params_file(SHIPPED.name) == mine  # ./studies first
    for find in (find_params_file, find_rule_file):
        with pytest.raises(InputFileError, match="is a directory"):
            find(str(tmp_path))
        with pytest.raises(DataMissingError, match="not found"):
            find("no_such_file.json")


@pytest.mark.parametrize("options, phrase", [
    ({"r_scale_pos": 2.0}, "options.r_scale_pos: an old name: the multiplier is now 'r_pos'"),
    ({"r_scale": 2.0}, "options.r_scale: an old name: the multiplier is now 'r_all'"),
    ({"r_pos": 0.0}, "options.r_pos: must be a number in [1e-06"),
    ({"q_att": 2.0}, "ekf-scaled: options q_att scale Q"),
    ({"r_bogus": 2.0}, "options.r_bogus: unknown parameter of ekf-scaled (known: r_all, "
                       "r_<channel>)"),
])
def test_ekf_scaled_options_use_the_one_vocabulary(options, phrase):
    from fuzzynav.errors import FuzzynavError
    from fuzzynav.filters.named import FilterContext, get_filter

    with pytest.raises(FuzzynavError) as exc:
        get_filter("ekf-scaled").make(FilterContext(options=options))
    assert phrase in str(exc.value)


def test_an_alias_of_a_filter_with_parameters_reads_its_file_too():
    from fuzzynav.filters.named import FILTERS, parse_filter_spec, register_alias

    FILTERS.load()
    try:
        register_alias("ekf-tuned-alias", "ekf-tuned")
        assert FILTERS["ekf-tuned-alias"].takes_params
        assert parse_filter_spec(f"ekf-tuned-alias@{SHIPPED}") == ("ekf-tuned-alias",
                                                                   {"params": str(SHIPPED)})
    finally:
        dict.pop(FILTERS, "ekf-tuned-alias", None)
