"""``fuzzynav compare <alignment scenario>``: the table, the claims, JSON and bad input."""
import json

from fuzzynav.cli import main

SHORT = """kind = "alignment"
base = "paper002"
name = "paper002-short"
duration_s = 60.0
threshold_arcmin = 120.0
[imu]
rate_hz = 10.0
"""


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_compare_dispatches_alignment_scenarios_and_prints_the_claims(capsys, tmp_path):
    scn = tmp_path / "short.toml"
    scn.write_text(SHORT)
    code, out, _ = _run(capsys, "compare", str(scn), "--filters", "align-kf,align-fuzzy",
                        "--mc", "2")
    assert code == 0
    assert "azimuth alignment time [s]" in out and "align-fuzzy vs align-kf" in out
    assert "threshold 120 arcmin" in out and "runs never within" in out
    code, out, _ = _run(capsys, "compare", str(scn), "--filters", "align-kf,align-kf12",
                        "--json", "--align-threshold", "90")
    doc = json.loads(out)
    assert code == 0 and doc["threshold_arcmin"] == 90.0
    t = doc["filters"]["align-kf"]["align_time_s"]["mean"]
    assert 0.0 <= t <= 60.0


def test_paper002_claims_are_printed_beside(capsys):
    # the built-in family name carries the paper's claims
    code, out, _ = _run(capsys, "compare", "paper002", "--filters", "align-kf,align-kf12",
                        "--align-threshold", "600")
    assert code == 0 and "paper KF (claim)" in out and "> 300" in out


def test_bad_alignment_input_is_one_line(capsys, tmp_path):
    scn = tmp_path / "bad.toml"
    scn.write_text(SHORT + "lat_deg = 95.0\n")
    code, _, err = _run(capsys, "compare", str(scn), "--filters", "align-kf,align-fuzzy")
    assert code == 2 and "lat_deg" in err and str(scn) in err and err.count("\n") == 1
    code, _, err = _run(capsys, "compare", "paper002", "--filters", "align-kf,nope")
    assert code == 2 and "unknown alignment filter 'nope'" in err


def test_run_align_chains_alignment_and_navigation(capsys, sim_cache):
    code, out, _ = _run(capsys, "run", "paper000-nominal", "--filter", "ekf", "--align",
                        "align-kf", "--cache", str(sim_cache))
    assert code == 0 and "aligned with align-kf" in out and "until 60 s" in out
    level = float(next(line for line in out.splitlines()
                        if line.startswith("aligned level error")).split()[-1])
    # the level limit is the accelerometer bias over g: 100 ug -> 0.0057 deg per axis
    assert level < 0.02
    assert "heading (deg)" in out
    code, _, err = _run(capsys, "run", "paper000-nominal", "--align", "nope", "--cache",
                        str(sim_cache))
    assert code == 2 and "unknown alignment filter 'nope'" in err


def test_options_that_mean_nothing_for_alignment_are_refused(capsys, tmp_path):
    for argv, fragment in [
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--plot",
          str(tmp_path)], "--plot: not available with alignment"),
        (["compare", "paper000", "--filters", "ekf,fakf", "--align-threshold", "5"],
         "--align-threshold: only for alignment scenarios"),
        (["run", "paper000", "--align", "align-kf", "--t-start", "100"],
         "--t-start: not available"),
        (["run", "--data", "rtklib:nowhere", "--align", "align-kf"], "--align: only with"),
    ]:
        code, _, err = _run(capsys, *argv)
        assert code == 2 and fragment in err and err.count("\n") == 1, (argv, err)


def test_scenarios_lists_the_alignment_family_and_filters(capsys):
    code, out, _ = _run(capsys, "scenarios")
    assert code == 0
    for name in ("paper002-sway", "paper002-mems", "align-fuzzy-fast", "align-kf12"):
        assert name in out


ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
ROR = ROOT / "rules" / "paper002_ror.json"
GPS = ROOT / "rules" / "paper000_gps_sins.json"


def _one_in_one_out_of_another_adapter(tmp_path):
    """paper002's ROR -> t controller relabelled as an exponential-weighting one."""
    doc = json.loads(ROR.read_text())
    doc["binding"]["adapter"] = "exponential-weighting"
    path = tmp_path / "ew.json"
    path.write_text(json.dumps(doc))
    return path


def _negative_factor(tmp_path):
    doc = json.loads(ROR.read_text())
    out = doc["outputs"][0]
    lo, hi = out["range"]
    out["range"] = [-hi, hi]
    path = tmp_path / "neg.json"
    path.write_text(json.dumps(doc))
    return path


def test_alignment_rule_files_and_options_are_checked(capsys, tmp_path):
    ew, neg = _one_in_one_out_of_another_adapter(tmp_path), _negative_factor(tmp_path)
    for argv, fragment in [
        (["compare", "paper002", "--filters", "align-kf,align-kf"], "names align-kf twice"),
        (["compare", "paper000", "--filters", "ekf,fakf,ekf"], "names ekf twice"),
        (["compare", "paper002", "--filters", "align-kf,align-kf12", "--rules", ROR],
         "--rules: no filter of align-kf, align-kf12 takes a rule file"),
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--rules", GPS],
         "$.binding.adapter: this policy needs adapter 'r-scaling'"),
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--rules", ew],
         "$.binding.adapter: this policy needs adapter 'r-scaling'; the rule file is bound "
         "to 'exponential-weighting'"),
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--rules", neg],
         "$.outputs[0].range: output 't' spans [-"),
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--align-threshold",
          "inf"], "--align-threshold must be in (0, 10800]"),
        (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--align-threshold",
          "nan"], "--align-threshold must be in (0, 10800]"),
        (["run", "paper000-nominal", "--align", f"align-kf@{ROR}"], "align-kf takes no rule"),
        (["run", "paper000-nominal", "--align", "align-fuzzy@"], "no rule file after '@'"),
        (["run", "paper000-nominal", "--align", f"align-fuzzy@{ew}"], "needs adapter 'r-scaling'"),
        (["run", "paper000-nominal", "--filter", "ekf", "--align", "align-fuzzy", "--rules",
          ROR], "--rules: filter 'ekf' takes no rule files"),
    ]:
        code, out, err = _run(capsys, *map(str, argv))
        assert code == 2 and fragment in err and err.count("\n") == 1, (argv, err)
        assert out == ""


class _Called(Exception):
    pass


def test_rules_go_to_the_navigation_filter_and_align_at_to_the_aligner(capsys, monkeypatch):
    """``--rules`` used to go to a fuzzy aligner, leaving fakf on its default rules."""
    import fuzzynav.align.chain as chain

    seen = {}

    def fake(log, nav_filter, options=None, align_filter="align-kf", rules=None):
        seen.update(nav=nav_filter, options=options, aligner=align_filter, rules=rules)
        raise _Called

    monkeypatch.setattr(chain, "run_aligned", fake)
    monkeypatch.setattr("fuzzynav.sim.sensor_log.simulate", lambda *a, **k: None)
    try:
        main(["run", "paper000-nominal", "--filter", "fakf", "--align", f"align-fuzzy@{ROR}",
              "--rules", str(GPS)])
    except _Called:
        pass
    assert seen == {"nav": "fakf", "options": {"rules": [str(GPS)]},
                    "aligner": "align-fuzzy", "rules": str(ROR)}
