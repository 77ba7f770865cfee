"""Writer of synthetic A-KIT recordings for the tests (the layout of ../shared/datasets/akit).

:func:`write_akit` turns a simulated trajectory into ``IMU_trajectoryN.csv`` (body FRD with
the y columns reversed, as the real files are) and ``corrected/GT_`` / ``DVL_trajectoryN.csv``
(NED, ZYX Euler; the reference stamped ``lag`` s late and its clock running ``rate`` times
the IMU's: fractional and negative lags allowed), so that the loader's conventions and its
clock map are checked against a truth we know.
"""
import numpy as np

from fuzzynav.nav import attitude
from fuzzynav.sim.segments import Segment
from fuzzynav.sim.trajectory import generate

SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
START = np.array([0.5733, 0.6090, -20.0])  # lat, lon [rad], h (the Haifa area)
HEAD = {"IMU": "Time [s],ACC X [m/s^2],ACC Y [m/s^2],ACC Z [m/s^2],GYRO X [rad/s],"
               "GYRO Y [rad/s],GYRO Z [rad/s]",
        "DVL": "Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]",
        "GT": "Time [s],Longitude [rad],Latitude [rad],Altitude [m],V North [m/s],"
              "V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]"}


def auv_trajectory(duration_s=120.0):
    segs = [Segment("turn", 20, turn_deg=60), Segment("cruise", 20),
            Segment("turn", 20, turn_deg=-90), Segment("climb", 30, pitch_deg=-5),
            Segment("turn", duration_s - 90, turn_deg=120)]
    return generate(START, segs, 100.0, 2.0, 0.5)


def varied_auv_trajectory():
    """120 s of turns while the speed changes (1.5-2.5 m/s): the forward velocity carries
    timing, and the body velocity changes within a second (a reference epoch a second off
    the DVL's shows it)."""
    segs = [Segment("accelerate", 10, speed_change_mps=0.5), Segment("turn", 15, turn_deg=60),
            Segment("accelerate", 10, speed_change_mps=-1.0), Segment("turn", 15, turn_deg=-90),
            Segment("accelerate", 10, speed_change_mps=0.8), Segment("turn", 20, turn_deg=120),
            Segment("accelerate", 10, speed_change_mps=-0.6), Segment("turn", 15, turn_deg=-60),
            Segment("accelerate", 15, speed_change_mps=0.5)]
    return generate(START, segs, 100.0, 2.0, 0.5)


def _euler_frd_ned(q_bn):
    out = []
    for C in attitude.quat_to_dcm(q_bn):
        F = SWAP @ C @ SWAP
        out.append([np.arctan2(F[2, 1], F[2, 2]), -np.arcsin(F[2, 0]),
                    np.arctan2(F[1, 0], F[0, 0])])
    return np.array(out)


def _write(path, kind, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [HEAD[kind]] + [",".join(repr(float(x)) for x in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def truth_at(tr, t):
    """The simulated truth at times ``t`` between its samples (clamped to its span):
    position and velocity linear, attitude along the rotation between the samples."""
    t = np.clip(t, tr.time_s[0], tr.time_s[-1])
    k = np.clip(np.searchsorted(tr.time_s, t, side="right") - 1, 0, tr.time_s.size - 2)
    f = ((t - tr.time_s[k]) / (tr.time_s[k + 1] - tr.time_s[k]))[:, None]
    rel = attitude.quat_to_rotvec(attitude.quat_multiply(attitude.quat_conj(tr.q_bn[k]),
                                                         tr.q_bn[k + 1]))
    q = attitude.quat_multiply(tr.q_bn[k], attitude.rotvec_to_quat(f * rel))
    return ((1 - f) * tr.lla[k] + f * tr.lla[k + 1], (1 - f) * tr.vel_n[k] + f * tr.vel_n[k + 1],
            q)


def _point_samples(t, inc):
    """Rates at the sample times from increments over the intervals between them: the mean
    of the two intervals' rates (an interval's own rate would sit half a sample later)."""
    r = inc / np.diff(t)[:, None]
    return np.vstack([r[:1], 0.5 * (r[1:] + r[:-1]), r[-1:]])


def lever_point(tr, t, lla, vel, q, lever_y):
    """Position and velocity (ENU) of the point ``lever_y`` m forward of the IMU at times
    ``t``: ``p + C_bn r``, ``v + C_bn (omega_b x r)`` (earth rate neglected, as the loader)."""
    w_b = np.column_stack([np.interp(t, tr.time_s, w) for w in
                           _point_samples(tr.time_s, tr.dtheta_b).T])
    r_b = np.array([0.0, lever_y, 0.0])
    C = attitude.quat_to_dcm(q)
    d_n, dv_n = C @ r_b, np.einsum("kij,kj->ki", C, np.cross(w_b, r_b))
    radius = 6378137.0 + lla[:, 2]
    lla = lla + np.column_stack([d_n[:, 1] / radius, d_n[:, 0] / (radius * np.cos(lla[:, 0])),
                                 d_n[:, 2]])
    return lla, vel + dv_n


def write_akit(directory, tr, n=1, lag=1.0, rate=1.0, lever_y=0.0, dvl_on_imu_clock=True):
    """Write trajectory ``n``: the GT row stamped ``s`` holds the truth at ``(s - lag) / rate``
    of a point ``lever_y`` m forward of the IMU; the DVL (the IMU point's velocity) is on
    the IMU clock, or with ``dvl_on_imu_clock=False`` on the reference's (as the real
    files': its row stamped ``s`` holds the velocity at the same time as the GT row);
    returns the 1-Hz truth indices of the DVL/GT rows."""
    rates, force = _point_samples(tr.time_s, tr.dtheta_b), _point_samples(tr.time_s, tr.dv_b)
    flip = np.array([1.0, -1.0, 1.0])
    _write(directory / f"IMU_trajectory{n}.csv", "IMU",
           np.column_stack([tr.time_s, (force @ SWAP.T) * flip, (rates @ SWAP.T) * flip]))
    idx = np.arange(0, tr.time_s.size, 100)
    t_gt = (tr.time_s[idx] - lag) / rate
    lla, vel, q = truth_at(tr, t_gt)
    if dvl_on_imu_clock:
        q_dvl, vel_dvl = tr.q_bn[idx], tr.vel_n[idx]
    else:
        q_dvl, vel_dvl = q, vel
    v_b = np.einsum("kji,kj->ki", attitude.quat_to_dcm(q_dvl), vel_dvl)
    _write(directory / "corrected" / f"DVL_trajectory{n}.csv", "DVL",
           np.column_stack([tr.time_s[idx], v_b @ SWAP.T]))
    lla, vel = lever_point(tr, np.clip(t_gt, tr.time_s[0], tr.time_s[-1]), lla, vel, q, lever_y)
    _write(directory / "corrected" / f"GT_trajectory{n}.csv", "GT",
           np.column_stack([tr.time_s[idx], lla[:, 1], lla[:, 0], lla[:, 2], vel @ SWAP.T,
                            _euler_frd_ned(q)]))
    return idx
