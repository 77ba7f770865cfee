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
        (["run", "paper000", "--align", "align-kf", "--json"], "--json: not available"),
        (["run", "--data", "rtklib:nowhere", "--align", "align-kf"], "--align: only with"),
    ]:
        code, _, err = _run(capsys, *argv)
        assert code == 2 and fragment in err and err.count("\n") == 1, (argv, err)


def test_scenarios_lists_the_alignment_family_and_filters(capsys):
    code, out, _ = _run(capsys, "scenarios")
    assert code == 0
    for name in ("paper002-sway", "paper002-mems", "align-fuzzy-fast", "align-kf12"):
        assert name in out
