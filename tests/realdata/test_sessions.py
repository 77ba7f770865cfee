"""Several recordings in one directory: ``--data rtklib:DIR:SESSION`` chooses one.

Without SESSION the loader refuses with one line listing the sessions; with it the
protocol runs on that session's files.
"""
import contextlib
import io

import pytest

from fuzzynav.cli import main
from fuzzynav.errors import DataMissingError, FuzzynavError
from fuzzynav.realdata.sources import parse_data_spec
from tests.realdata.rtklib_files import write_drive

ARGS = ("--filter", "ekf", "--outage-period", "30", "--outage-duration", "10",
        "--first-outage", "20")


def run_cli(spec):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["run", "--data", spec, *ARGS])
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def two_sessions(tmp_path_factory):
    d = tmp_path_factory.mktemp("sessions")
    write_drive(d, sid="1")
    write_drive(d, sid="2", tick0=9000)
    return d


def _one_line_error(code, out, err):
    return code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err


def test_without_a_session_one_error_lists_them(two_sessions):
    code, out, err = run_cli(f"rtklib:{two_sessions}")
    assert _one_line_error(code, out, err), err
    assert "imu_1.csv, imu_2.csv" in err and "choose a session (1, 2)" in err
    assert "--data KIND:DIR:SESSION" in err


@pytest.mark.parametrize("session, words", [("7", "no session '7' (no imu_7.csv); "
                                                   "sessions here: 1, 2"),
                                            ("*", "'*' is not a session id"),
                                            ("x/../1", "'x/../1' is not a session id")])
def test_an_unknown_or_odd_session_is_named(two_sessions, session, words):
    code, out, err = run_cli(f"rtklib:{two_sessions}:{session}")
    assert _one_line_error(code, out, err) and words in err, err


def test_with_a_session_it_runs(two_sessions):
    code, out, err = run_cli(f"rtklib:{two_sessions}:2")
    assert code == 0, err
    assert out.startswith(f"recording rtklib:{two_sessions}:2: ")
    assert "horizontal position RMS (m)" in out


def test_the_spec_is_split_at_the_last_colon_unless_the_directory_exists(tmp_path):
    plain = tmp_path / "drive"
    plain.mkdir()
    _, path, session = parse_data_spec(f"rtklib:{plain}:1934")
    assert (path, session) == (plain, "1934")
    _, path, session = parse_data_spec(f"rtklib:{plain}")
    assert (path, session) == (plain, None)
    odd = tmp_path / "a:b"  # a directory whose name has a colon is taken whole
    odd.mkdir()
    _, path, session = parse_data_spec(f"rtklib:{odd}")
    assert (path, session) == (odd, None)
    with pytest.raises(FuzzynavError, match="KIND:DIR:SESSION"):
        parse_data_spec(f"rtklib:{plain}:")
    with pytest.raises(DataMissingError, match="recording directory not found"):
        parse_data_spec(f"rtklib:{tmp_path / 'none'}:1")


@pytest.mark.parametrize("names, session, expect", [
    (["gnss_1_sf.pos", "gnss_12_sf.pos"], "1", "gnss_1_sf.pos"),
    (["gnss_1.pos", "gnss_12.pos"], "1", "gnss_1.pos"),
    (["gnss_1_sf.pos", "gnss_12_sf.pos"], "12", "gnss_12_sf.pos"),
    (["gnss_1-rtk.pos", "gnss_1a.pos"], "1", "gnss_1-rtk.pos"),
])
def test_a_session_takes_only_its_own_gnss_solution(tmp_path, names, session, expect):
    """``gnss_<id>*.pos`` must not reach into another session whose id starts with this
    one's (session 1 and session 12 in one directory)."""
    from fuzzynav.realdata.loaders.recording_files import find_files

    for sid in {session, "12"}:
        (tmp_path / f"imu_{sid}.csv").write_text("x\n")
        (tmp_path / f"imu_{sid}.csv.tag").write_bytes(b"x")
    for n in names:
        (tmp_path / n).write_text("x\n")
    assert find_files(tmp_path, session)["pos"].name == expect
