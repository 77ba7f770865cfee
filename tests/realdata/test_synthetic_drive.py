"""The whole protocol on a simulated car "recording" whose errors are known (no data needed).

A car rests, accelerates to 10 m/s and drives straight north; its IMU is ideal except for an
accelerometer bias of ``B`` on the body's right axis (east) that appears exactly when the
outage starts.  The filter cannot know it, so the drift at the end of the outage is the
double integral of the bias, ``B (t - a)^2 / 2``, plus what the filter had not settled.
"""
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from fuzzynav.realdata.protocol import ProtocolSettings
from fuzzynav.realdata.validate import validate
from fuzzynav.sim.imu import ImuData
from fuzzynav.realdata.loaders.mounting import Mounting
from fuzzynav.sim.segments import Segment
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.trajectory import generate

B = 0.02                 # accelerometer bias step [m/s^2] (2 mg)
FIRST_OUTAGE_S = 60.0    # after the filter's start (the end of the rest, ~20 s)


def _recording(bias_step_at=None):
    traj = generate(np.array([np.radians(40.0), np.radians(-105.0), 1600.0]),
                    [Segment("static", 20.0), Segment("accelerate", 10.0, speed_change_mps=10.0),
                     Segment("cruise", 130.0)], 100.0)
    dv = traj.dv_b.copy()
    if bias_step_at is not None:
        k = traj.time_s[:-1] >= bias_step_at - 1e-9
        dv[k, 0] += B * np.diff(traj.time_s)[k]
    imu = ImuData(time_s=traj.time_s, dtheta_b=traj.dtheta_b, dv_b=dv)
    sel = slice(None, None, 25)                       # 4-Hz fixes from the truth
    z = np.column_stack([traj.lla[sel], traj.vel_n[sel]])
    sigma = np.tile([0.01, 0.01, 0.02, 0.02, 0.02, 0.03], (z.shape[0], 1))
    fixes = SensorData("gnss", traj.time_s[sel].copy(), z, sigma,
                       {"lever_arm_b": np.zeros(3)})
    return SimpleNamespace(imu=imu, gnss=fixes, reference=fixes, mounting=Mounting(),
                           directory=Path("synthetic"))


SETTINGS = ProtocolSettings(noise_pos_m=2.0, velocity="raw", velocity_lag_s=0.0,
                            first_outage_s=FIRST_OUTAGE_S)


@pytest.fixture(scope="module")
def clean():
    return validate(_recording(), "ekf", SETTINGS, seed=3)


def test_windows_follow_the_start_found_in_the_data(clean):
    # the rest ends when the car starts to accelerate (20 s), to within one 0.5-s block
    assert abs(clean.start.init.time_s - 20.0) <= 0.5
    np.testing.assert_allclose(clean.windows[0], clean.start.init.time_s
                               + np.array([FIRST_OUTAGE_S, FIRST_OUTAGE_S + 60.0]))
    assert [d.complete for d in clean.runs["outages"].drifts] == [True]


def test_aided_error_is_below_the_added_noise(clean):
    # raw fixes with 2 m per axis have a horizontal RMS of 2.83 m; the filter, also fed
    # (ideal) velocities, must do better
    for run in clean.runs.values():
        assert run.metrics["rms_pos_h_aided_m"] < 2.0 * np.sqrt(2.0) / 2
        assert run.result.ok


def test_ideal_imu_hardly_drifts(clean):
    # nothing but estimation error is left (velocity error of cm/s over 60 s: < 1 m)
    assert clean.runs["outages"].drifts[0].drift_h_m < 1.0


def test_drift_of_a_bias_step_is_its_double_integral(clean):
    a = clean.windows[0, 0]
    v = validate(_recording(bias_step_at=a), "ekf", SETTINGS, seed=3)
    d = v.runs["outages"].drifts[0]
    expected = 0.5 * B * (d.t_read_s - a) ** 2                    # 35.7 m at 59.75 s
    # the ideal-IMU run's drift bounds what the filter adds (same noise, same start)
    assert abs(d.drift_h_m - expected) < clean.runs["outages"].drifts[0].drift_h_m + 0.5
    # with GNSS throughout the step is estimated away instead
    assert v.runs["gnss"].metrics["rms_pos_h_aided_m"] < 1.5
