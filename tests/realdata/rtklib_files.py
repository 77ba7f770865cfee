"""Writers of synthetic RTKLIB recordings for the tests: ``imu_<id>.csv`` + ``.tag`` + ``.pos``.

:func:`write_imu` writes a CSV of rate samples and the time tag a logger would have written
beside it (the file size reached at chunk instants of the PC clock); :func:`write_pos` a
geodetic RTKLIB solution; :func:`write_drive` a whole, physically consistent car recording
(rest, drive off, two turns) from the trajectory simulator, which the loader and the
``fuzzynav run --data`` protocol accept — the undamaged original of the damaged-recording
corpus.
"""
import struct
import time

import numpy as np

from fuzzynav.sim.segments import Segment
from fuzzynav.sim.trajectory import generate

START = (1_700_000_000, 0.25)    # GPST of the tag file (seconds since 1970, GPS scale)
G0 = 9.80665                      # standard gravity: the CSV holds g


def tag_bytes(records, start=(1752003261, 0.854), tick_f=7) -> bytes:
    """A time-tag file: header, then the (tick ms, file position) records."""
    head = b"TIMETAG RTKLIB demo5".ljust(60, b"\0") + struct.pack("<IId", tick_f, *start)
    return head + b"".join(struct.pack("<II", int(t), int(p)) for t, p in records)


def csv_lines(acc_g, gyro_dps, ticks) -> list:
    """CSV lines (no line end) of acc x,y,z [g], gyro x,y,z [deg/s], tick [ms]."""
    return [f"{a[0]:.6f},{a[1]:.6f},{a[2]:.6f},{w[0]:.6f},{w[1]:.6f},{w[2]:.6f},{int(k)}"
            for a, w, k in zip(acc_g, gyro_dps, ticks)]


def write_imu(directory, lines, arrival_ms, start=START, crlf_stripped=True, sid="1",
              chunk_ms=15.5, first_chunk_ms=130.0, fpos_scale=1.0, partial_record=True):
    """Write ``imu_<sid>.csv`` (logged with CR LF) and its tag.

    ``arrival_ms[i]`` is when line ``i`` reached the logger (PC ms since the tag start); a
    record every ``chunk_ms`` holds the size the file had reached (``fpos_scale`` != 1
    spoils it).  A trailing partial record is appended, as an interrupted write leaves.
    """
    logged = "".join(line + "\r\n" for line in lines).encode()
    stored = logged.replace(b"\r\n", b"\n") if crlf_stripped else logged
    (directory / f"imu_{sid}.csv").write_bytes(stored)
    ends = np.cumsum([len(line) + 2 for line in lines])
    chunks = np.arange(first_chunk_ms, arrival_ms[-1] + chunk_ms, chunk_ms)
    fpos = [int(ends[arrival_ms <= c].max(initial=0) * fpos_scale) for c in chunks]
    tail = b"\x01\x02" if partial_record else b""
    (directory / f"imu_{sid}.csv.tag").write_bytes(
        tag_bytes(zip(chunks, fpos), start=start, tick_f=123) + tail)


POS_HEADER = ("%  GPST          latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)"
              "   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio    vn(m/s)    ve(m/s)    "
              "vu(m/s)      sdvn     sdve     sdvu    sdvne    sdveu    sdvun\n")


def _gpst_text(t_s: float) -> str:
    whole = int(np.floor(t_s + 5e-4))
    return time.strftime("%Y/%m/%d %H:%M:%S", time.gmtime(whole)) + \
        f".{int(round((t_s - whole) * 1000)):03d}"


def write_pos(path, t_gpst_s, lla_deg, vel_enu, q, sd=(0.010, 0.011, 0.02),
              sdv=(0.05, 0.06, 0.07)):
    """An RTKLIB llh solution (GPST) with the velocity block.

    Parameters
    ----------
    t_gpst_s : array (N,), GPST seconds since 1970
    lla_deg : array (N, 3), latitude [deg], longitude [deg], height [m]
    vel_enu : array (N, 3) [m/s]
    q : array (N,) of quality flags
    sd, sdv : sigma north, east, up of position [m] and velocity [m/s]
    """
    rows = [f"{_gpst_text(t)} {p[0]:.10f} {p[1]:.10f} {p[2]:.4f} {int(qk)} 20 {sd[0]:.3f} "
            f"{sd[1]:.3f} {sd[2]:.3f} 0 0 0 0.0 0.0 {v[1]:.4f} {v[0]:.4f} {v[2]:.4f} "
            f"{sdv[0]:.3f} {sdv[1]:.3f} {sdv[2]:.3f} 0 0 0\n"
            for t, p, v, qk in zip(t_gpst_s, lla_deg, vel_enu, q)]
    path.write_text("% program : test\n% obs start : GPST\n" + POS_HEADER + "".join(rows))


# -- a whole car recording ----------------------------------------------------------------------
#: the loader's default IMU delay (0.21 s) less the mean chunking wait, so that the loaded
#: sample times are the true ones
DRIVE_LATENCY_MS = 210.0 - 15.5 / 2
DRIVE_SEGMENTS = (Segment("static", 20.0), Segment("accelerate", 8.0, speed_change_mps=8.0),
                  Segment("turn", 10.0, turn_deg=90.0), Segment("cruise", 8.0),
                  Segment("turn", 10.0, turn_deg=-120.0), Segment("cruise", 8.0))
DRIVE_RATE_HZ = 100.0
DRIVE_HEADING_DEG = 30.0
#: a walk at 1.4 m/s with a stop: a recording the car defaults refuse (never 2 m/s)
WALK_SEGMENTS = (Segment("static", 20.0), Segment("accelerate", 2.0, speed_change_mps=1.4),
                 Segment("cruise", 20.0), Segment("turn", 10.0, turn_deg=90.0),
                 Segment("cruise", 15.0), Segment("accelerate", 2.0, speed_change_mps=-1.4),
                 Segment("static", 8.0), Segment("accelerate", 2.0, speed_change_mps=1.4),
                 Segment("cruise", 15.0), Segment("turn", 10.0, turn_deg=-90.0),
                 Segment("cruise", 30.0))


def drive_samples(segments=DRIVE_SEGMENTS):
    """Truth trajectory of the drive and its rate samples: ``traj, acc_g, gyro_dps``.

    The rates of each sample interval (increment / dt), placed at the interval's end;
    the body frame (RFU) is the IMU frame.
    """
    traj = generate(np.array([np.radians(40.0), np.radians(-105.0), 1600.0]),
                    list(segments), DRIVE_RATE_HZ,
                    initial_heading_rad=np.radians(DRIVE_HEADING_DEG))
    dt = np.diff(traj.time_s)[:, None]
    acc_g = np.vstack([traj.dv_b[:1], traj.dv_b]) / np.vstack([dt[:1], dt]) / G0
    gyro = np.degrees(np.vstack([traj.dtheta_b[:1], traj.dtheta_b]) / np.vstack([dt[:1], dt]))
    return traj, acc_g, gyro


def write_drive(directory, sid="1", tick0=5000, segments=DRIVE_SEGMENTS):
    """Write the drive (or another motion, ``segments``) into ``directory``; return the truth
    trajectory.

    100-Hz IMU (ticks in ms, no jitter), lines arriving :data:`DRIVE_LATENCY_MS` after
    their sample, 4-Hz RTK-fixed solution from the truth at the same GPST instants.
    """
    traj, acc_g, gyro = drive_samples(segments)
    t_ms = traj.time_s * 1000.0
    write_imu(directory, csv_lines(acc_g, gyro, tick0 + np.rint(t_ms)),
              DRIVE_LATENCY_MS + t_ms, sid=sid)
    sel = slice(0, None, int(DRIVE_RATE_HZ / 4))
    lla = np.column_stack([np.degrees(traj.lla[sel, :2]), traj.lla[sel, 2]])
    t_gpst = START[0] + START[1] + traj.time_s[sel]
    write_pos(directory / f"gnss_{sid}_sf.pos", t_gpst, lla, traj.vel_n[sel],
              np.ones(lla.shape[0], dtype=int))
    return traj
