"""``fuzzynav scenarios | run | compare``: output, JSON, plots and one-line errors (exit 2)."""
import json

import pytest

from fuzzynav.cli import main


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_scenarios_lists_builtins_and_filters(capsys):
    code, out, _ = _run(capsys, "scenarios")
    assert code == 0
    for name in ("paper000", "paper000-nominal", "ekf", "fakf", "sage-husa", "ekf-true"):
        assert name in out


def test_run_prints_every_axis_and_json(capsys, sim_cache):
    code, out, _ = _run(capsys, "run", "paper000-nominal", "--filter", "ekf", "--cache",
                        str(sim_cache))
    assert code == 0
    for label in ("east position (m)", "up velocity (m/s)", "pitch (deg)", "heading (deg)"):
        assert label in out
    code, out, _ = _run(capsys, "run", "paper000-nominal", "--filter", "ekf", "--json",
                        "--cache", str(sim_cache))
    doc = json.loads(out)
    m = doc["filters"]["ekf"]["rms_pos_e_m"]
    assert code == 0 and 0.0 < m["mean"] < 5.0 and len(m["values"]) == 1


def test_compare_shows_intervals_improvements_and_claims(capsys, sim_cache, tmp_path):
    code, out, _ = _run(capsys, "compare", "paper000", "--filters", "ekf,fakf", "--mc", "2",
                        "--cache", str(sim_cache), "--plot", str(tmp_path))
    assert code == 0
    assert "±" in out and "fakf vs ekf" in out and "paper EKF (claim)" in out
    assert "5.7305" in out  # the paper's own number, printed beside ours
    assert (tmp_path / "paper000_errors.png").stat().st_size > 10_000
    assert (tmp_path / "paper000_adaptation.png").exists()


@pytest.mark.parametrize("argv,fragment", [
    (["run", "no-such-scenario"], "unknown scenario 'no-such-scenario'"),
    (["run", "paper000", "--filter", "nope"], "unknown filter 'nope'"),
    (["run", "paper000", "--mc", "0"], "--mc must be >= 1"),
    (["run"], "give either a SCENARIO or --data"),
    (["compare", "paper000", "--filters", "ekf"], "at least two"),
    (["run", "missing_dir/scn.toml"], "scenario file not found"),
])
def test_errors_are_one_line_with_exit_code_2(capsys, argv, fragment, sim_cache):
    code, out, err = _run(capsys, *argv, "--cache", str(sim_cache))
    assert code == 2
    assert fragment in err and err.count("\n") == 1 and err.startswith("fuzzynav: error:")


def test_malformed_scenario_file_names_file_and_key(capsys, tmp_path, sim_cache):
    bad = tmp_path / "bad.toml"
    bad.write_text('base = "paper000"\n[sensors.gps]\nrate_hz = -1.0\n')
    code, _, err = _run(capsys, "run", str(bad), "--cache", str(sim_cache))
    assert code == 2 and "bad.toml" in err and "sensors.gps.rate_hz" in err
    bad.write_text("this is = = not toml")
    code, _, err = _run(capsys, "run", str(bad), "--cache", str(sim_cache))
    assert code == 2 and "invalid TOML" in err


def test_compare_a_filter_with_its_own_rule_files(capsys, sim_cache):
    code, out, _ = _run(capsys, "compare", "paper000-nominal", "--filters",
                        "ekf,fakf@rules/paper002_ror_gnss.json", "--cache", str(sim_cache))
    assert code == 0 and "fakf@rules/paper002_ror_gnss.json vs ekf" in out
    code, _, err = _run(capsys, "compare", "paper000-nominal", "--filters",
                        "ekf,fakf@rules/none.json", "--cache", str(sim_cache))
    assert code == 2 and "none.json" in err
