"""``fuzzynav run --data akit:DIR:N`` on a synthetic recording: JSON layout, errors."""
import json

import numpy as np
import pytest

from tests.realdata.test_cli_errors import _run
from tests.realdata.akit_files import auv_trajectory, write_akit


@pytest.fixture(scope="module")
def two_trajectories(tmp_path_factory):
    d = tmp_path_factory.mktemp("akit-cli")
    tr = auv_trajectory()
    write_akit(d, tr, n=1, lag=1.0)
    write_akit(d, tr, n=2, lag=0.0)
    return d


def test_json_has_a_column_per_trajectory_and_the_pooled_one(two_trajectories):
    code, out, err = _run("run", "--data", f"akit:{two_trajectories}:1-2", "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["trajectories"] == [1, 2] and set(doc["feeds"]) == {"traj 1", "traj 2", "all"}
    pooled = doc["feeds"]["all"]["rms_pos_h_m"]
    np.testing.assert_allclose(pooled["mean"], np.mean(pooled["values"]), rtol=1e-12)
    # error-free synthetic IMU and DVL: the aided INS stays within a metre over 120 s
    assert max(pooled["values"]) < 1.0
    assert abs(doc["start"]["1"]["reference_offset_s"] - 1.0) < 0.005


def test_json_with_figures_is_one_json_document(two_trajectories, tmp_path):
    code, out, err = _run("run", "--data", f"akit:{two_trajectories}:1-2", "--json",
                          "--plot", str(tmp_path))
    assert code == 0, err
    assert json.loads(out)["trajectories"] == [1, 2] and "wrote" not in out
    notices = [line for line in err.splitlines() if line.startswith("wrote ")]
    assert notices and all(str(tmp_path) in line for line in notices)   # on stderr


def test_text_table_and_bad_options(two_trajectories):
    code, out, _ = _run("run", "--data", f"akit:{two_trajectories}:2")
    assert code == 0 and "as % of the distance travelled" in out and "traj 2" in out
    code, _, err = _run("run", "--data", f"akit:{two_trajectories}:2", "--span", "0,10")
    assert code == 2 and "--span: does not apply to akit recordings" in err
    code, _, err = _run("run", "--data", f"akit:{two_trajectories}:5")
    assert code == 2 and "IMU_trajectory5.csv" in err and len(err.strip().splitlines()) == 1


def test_name_at_file_works_on_recordings(two_trajectories, tmp_path):
    """``--filter apso@FILE`` on an A-KIT recording uses the file (it used to work on
    scenarios only): same numbers as the file given as the filter's option, other numbers
    than apso's defaults (the file multiplies the DVL's R by 25)."""
    from fuzzynav.realdata.akit import run_trajectory
    from fuzzynav.realdata.loaders.akit_recording import load_trajectory

    params = tmp_path / "p.json"
    params.write_text(json.dumps({"format": "fuzzynav-baselines", "version": 1,
                                  "filters": {"apso": {"r_all": 25.0}}}))
    code, out, err = _run("run", "--data", f"akit:{two_trajectories}:2", "--json",
                          "--filter", f"apso@{params}")
    assert code == 0, err
    at_file = json.loads(out)["feeds"]["traj 2"]["rms_pos_h_m"]["values"][0]
    rec = load_trajectory(two_trajectories, 2)
    assert at_file == run_trajectory(rec, "apso", {"params": str(params)})[1]["rms_pos_h_m"]
    assert at_file != run_trajectory(rec, "apso")[1]["rms_pos_h_m"]


def test_chunk_files_of_each_trajectory_hold_its_runs_rows(two_trajectories, tmp_path):
    """``--output-dir`` on held A-KIT trajectories: DIR/FILTER-seed0/trajN/chunk-*.npz, the
    table the same as without it."""
    from fuzzynav.filters.chunk_files import read_chunks

    base = ("run", "--data", f"akit:{two_trajectories}:1-2", "--json", "--output-rate", "1")
    code, plain, err = _run(*base)
    assert code == 0, err
    code, out, err = _run(*base, "--output-dir", str(tmp_path / "out"))
    assert code == 0, err
    assert json.loads(out)["feeds"] == json.loads(plain)["feeds"]
    for n in (1, 2):
        got = read_chunks(tmp_path / "out" / "ekf-seed0" / f"traj{n}")
        assert np.all(np.diff(got.time_s) > 0.999) and set(got.events) == {"dvl"}
