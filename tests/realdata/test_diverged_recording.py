"""A filter that diverges on a recording: one line, exit 3, no table (docs/reliability.md)."""
import dataclasses
import json

import numpy as np
import pytest

from fuzzynav import runpath
from fuzzynav.realdata.validate import required_names
from tests.realdata.test_damaged_recordings import drive, run_cli  # noqa: F401 (fixture)


def _nan_from_halfway(monkeypatch):
    """Every filter run returns NaN positions from its middle on, as a diverged filter
    would, while still reporting that it ran to the end (patched in the one run path)."""
    real = runpath.run_filter

    def run(*args, **kwargs):
        res = real(*args, **kwargs)
        lla = res.lla.copy()
        lla[len(lla) // 2:] = np.nan
        return dataclasses.replace(res, lla=lla)

    monkeypatch.setattr(runpath, "run_filter", run)


@pytest.mark.parametrize("extra", [(), ("--json",)], ids=["table", "json"])
def test_a_diverged_run_on_a_recording_exits_3_without_a_table(drive, monkeypatch,  # noqa: F811
                                                               extra):
    _nan_from_halfway(monkeypatch)
    code, out, err = run_cli(drive, *extra)
    assert code == 3, err
    assert out == ""  # no table, and no JSON with null in place of the NaN
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"filter ekf diverged on recording rtklib:{drive} (GNSS throughout) seed 0" in err
    assert "rms_pos_e_m = nan" in err and "2 of 2 run(s)" in err


def test_the_same_drive_without_the_fault_exits_0(drive):  # noqa: F811
    # its attitude RMS is NaN (no attitude truth on a recording): that must not trip it
    code, out, err = run_cli(drive, "--json")
    assert code == 0, err
    feeds = json.loads(out)["feeds"]
    assert feeds["GNSS throughout"]["rms_att_deg"]["mean"] is None
    assert np.isfinite(feeds["GNSS throughout"]["rms_pos_h_m"]["mean"])


def test_which_metrics_may_be_nan():
    two = {"rms_pos_h_m": 1.0, "rms_att_deg": np.nan, "rms_vel_mps": np.nan, "n_outages": 2.0,
           "drift_h_m_1": 3.0, "drift_h_m_2": 4.0, "drift_h_rms_m": 3.5}
    one = {**two, "n_outages": 1.0, "drift_h_m_2": np.nan}
    req = required_names(two, vel_scored=False)  # a reference without velocities
    assert "rms_att_deg" not in req and "rms_pos_h_aided_m" not in req
    assert "rms_pos_h_m" in req and "rms_vel_mps" not in req
    assert {"drift_h_m_1", "drift_h_m_2", "drift_h_rms_m"} <= set(req)
    # a run that completed only one outage: its second drift is legitimately NaN
    assert "drift_h_m_1" in required_names(one, False)
    assert "drift_h_m_2" not in required_names(one, False)
    assert "rms_vel_mps" in required_names(two, vel_scored=True)
