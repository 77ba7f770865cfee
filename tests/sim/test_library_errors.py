"""Library callers (not the CLI) get one clear FuzzynavError, not a bare ValueError/KeyError.

A Scenario built in Python gets the checks of a scenario file; seeds, names and a
recording's failed lag measurement are refused with the field (and the file) named.
"""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError, UnknownNameError
from fuzzynav.experiment import summary_table
from fuzzynav.realdata.validate import validate
from fuzzynav.realdata.loaders import sync
from fuzzynav.realdata.loaders.rtklib import load_rtklib
from fuzzynav.sim.sensor_log import check_seed, simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.segments import Segment
from tests.realdata.rtklib_files import write_drive

TINY = Path(__file__).resolve().parents[1] / "tuning" / "data" / "tiny.toml"


@pytest.fixture(scope="module")
def tiny():
    return load_scenario(TINY)


# -- Scenario(...) in Python ------------------------------------------------------------------
def test_a_valid_scenario_can_still_be_varied(tiny):
    other = replace(tiny, name="other", start_lat_deg=-30.0)
    assert other.start_lat_deg == -30.0 and other.duration_s == tiny.duration_s


@pytest.mark.parametrize("change, where, words", [
    # 1e9 s at 50 Hz = 5e10 samples: refused with the estimate, before any allocation
    (dict(segments=(Segment("cruise", 1e9),)), "imu.rate_hz", "samples needs ~"),
    (dict(start_lat_deg=89.9), "start.lat_deg", "of a pole"),
    (dict(start_lat_deg=120.0), "start.lat_deg", "is not a latitude"),
    (dict(start_lat_deg=float("nan")), "start.lat_deg", "must be a finite number"),
    (dict(start_h_m=float("inf")), "start.h_m", "must be a finite number"),
    (dict(initial_speed_mps=1e5), "start.speed_mps", "faster than"),
])
def test_a_python_scenario_gets_the_file_checks(tiny, change, where, words):
    with pytest.raises(InputFileError, match=words) as exc:
        replace(tiny, **change)
    assert exc.value.where == where


def test_a_python_scenario_gets_the_sensor_checks(tiny):
    fast = replace(tiny.sensors["gps"], rate_hz=2 * tiny.imu.rate_hz)
    with pytest.raises(InputFileError, match="above the IMU rate") as exc:
        replace(tiny, sensors={"gps": fast})
    assert exc.value.where == "sensors.gps.rate_hz"


def test_a_python_scenario_gets_the_motion_check(tiny):
    # a static segment while moving at 5 m/s: the trajectory builder refuses it
    with pytest.raises(InputFileError):
        replace(tiny, initial_speed_mps=5.0, segments=(Segment("static", 10.0),))


# -- seeds and names ----------------------------------------------------------------------------
@pytest.mark.parametrize("seed, shown", [(-1, "-1"), (1.5, "1.5"), ("3", "'3'")])
def test_bad_seeds_are_refused_by_simulate_and_validate(tiny, seed, shown):
    msg = f"seed: must be a non-negative integer, got {shown}"
    with pytest.raises(InputFileError, match=msg):
        simulate(tiny, seed)
    with pytest.raises(ValueError, match=msg):  # still a ValueError for callers catching it
        validate(None, "ekf", seed=seed)      # refused before the recording is looked at
    assert check_seed(np.int64(7)) == 7 and type(check_seed(np.int64(7))) is int


def test_summary_table_names_an_unknown_baseline_or_metric():
    df = pd.DataFrame([{"scenario": "s", "filter": f, "seed": k, "rms_pos_m": 1.0 + k}
                       for f in ("ekf", "fakf") for k in (0, 1)])
    table = summary_table(df, ["rms_pos_m"], baseline="ekf")
    assert table.loc["rms_pos_m", ("fakf", "improvement_pct")] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(UnknownNameError, match="unknown baseline filter 'akf'; known: ekf, "
                                               "fakf"):
        summary_table(df, ["rms_pos_m"], baseline="akf")
    with pytest.raises(KeyError, match="unknown metric 'rms_pos'; known: rms_pos_m"):
        summary_table(df, ["rms_pos"])


# -- a recording's lag that cannot be measured names the file ------------------------------------
def test_course_rate_lag_names_the_recording(tmp_path):
    write_drive(tmp_path)
    rec = load_rtklib(tmp_path, mounting=None)
    assert abs(sync.course_rate_lag(rec.imu, rec.reference)) < 0.05  # it does drive
    with pytest.raises(InputFileError, match="too few moving GNSS intervals") as exc:
        sync.course_rate_lag(rec.imu, rec.reference, t_range=(0.0, 15.0))  # the rest only
    assert exc.value.path == str(tmp_path / "imu_1.csv") and exc.value.where == "time alignment"
    with pytest.raises(FuzzynavError, match=r"^elsewhere\.csv: time alignment: "):
        sync.course_rate_lag(rec.imu, rec.reference, t_range=(0.0, 15.0),
                             source="elsewhere.csv")
