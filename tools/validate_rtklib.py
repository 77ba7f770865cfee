"""Figures of docs/validation.md: the filters on the rtklib-drive under the validation protocol.

Run by hand from the repository root: ``python tools/validate_rtklib.py [DATA_DIR]``
(DATA_DIR defaults to ``$FUZZYNAV_DATA/rtklib-drive``, ``FUZZYNAV_DATA`` to
``../shared/datasets``).  About two minutes.  Prints markdown tables and writes the two
figures into ``docs/figures/``; nothing is asserted (the tests do that).

The headline numbers can also be had from the CLI, e.g.::

    fuzzynav run --data rtklib:../shared/datasets/rtklib-drive --mounting rtklib-drive \\
        --filter ekf --mc 10 --plot docs/figures
"""
from __future__ import annotations

import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.runner import InitialState, run_filter
from fuzzynav.nav import attitude, earth
from fuzzynav.realdata.figures import write_figures
from fuzzynav.realdata.mems import CONSUMER_MEMS
from fuzzynav.realdata.protocol import ProtocolSettings
from fuzzynav.realdata.score import errors_against, horizontal
from fuzzynav.realdata.sources import SOURCES, resolve_mounting
from fuzzynav.realdata.validate import validate
from fuzzynav.realdata import coarse_align
from fuzzynav.report import ci_cell
from fuzzynav.sim.imu import ImuData

ROOT = Path(__file__).resolve().parents[1]
SEEDS = range(10)
FILTERS = ("ekf", "sage-husa", "vb", "fakf", "huber", "fading-memory")


def _load(directory, mounting="rtklib-drive", **kw):
    return SOURCES["rtklib"].load(directory, mounting=resolve_mounting(mounting), **kw)


def _cell(values, fmt=".2f") -> str:
    return ci_cell(values, fmt)


def _runs(rec, name, settings, seeds=SEEDS, mems=CONSUMER_MEMS):
    return [validate(rec, name, settings, s, mems=mems) for s in seeds]


def _col(vals, feed, key):
    return [v.runs[feed].metrics.get(key, np.nan) for v in vals]


def filters_table(rec, velocity="shift"):
    """The named filters under the default protocol, mean ± 95 % CI over noise seeds."""
    print(f"\n### Filters (velocities: {velocity}; {len(SEEDS)} noise seeds; "
          "mean ± 95 % CI)\n")
    print("| filter | horizontal RMS, GNSS throughout (m) | with outages: overall (m) | "
          "outside the outages (m) | drift, outage 1 (m) | drift, outage 2 (m) | "
          "drift RMS (m) | runs completed |")
    print("|---|---|---|---|---|---|---|---|")
    for name in FILTERS:
        vals = _runs(rec, name, ProtocolSettings(velocity=velocity))
        done = sum(v.runs["outages"].result.ok and v.runs["gnss"].result.ok for v in vals)
        print(f"| {name} | {_cell(_col(vals, 'gnss', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'outages', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'outages', 'rms_pos_h_aided_m'))} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_m_1'), '.0f')} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_m_2'), '.0f')} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_rms_m'), '.0f')} | "
              f"{done}/{len(vals)} |")
    w = vals[0].windows
    print(f"\nOutage windows: {', '.join(f'{a:.1f}-{b:.1f} s' for a, b in w)} "
          "(the last one runs past the end of the data and is not scored).")


def constraints_table(rec):
    """Non-holonomic constraints (zero lateral/vertical body velocity, 10 Hz) against none."""
    print("\n### Non-holonomic constraints (ekf, 10 noise seeds; mean ± 95 % CI)\n")
    print("| constraint sigma | horizontal RMS, GNSS throughout (m) | with outages (m) | "
          "drift, outage 1 (m) | drift, outage 2 (m) | drift RMS (m) |")
    print("|---|---|---|---|---|---|")
    for sigma in (0.0, 1.0, 0.3, 0.1):
        vals = _runs(rec, "ekf", ProtocolSettings(nhc_sigma_mps=sigma))
        label = "none" if sigma == 0.0 else f"{sigma:g} m/s"
        print(f"| {label} | {_cell(_col(vals, 'gnss', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'outages', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_m_1'), '.1f')} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_m_2'), '.1f')} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_rms_m'), '.1f')} |")


def velocity_modes(rec):
    """What to do with the lagging receiver velocities (ekf)."""
    print("\n### GNSS velocity: shift, raw, inflate, positions only (ekf, 10 seeds)\n")
    print("| velocities | horizontal RMS, GNSS throughout (m) | velocity RMS (m/s) | "
          "outside the outages (m) | drift RMS (m) |")
    print("|---|---|---|---|---|")
    cases = [(m, ProtocolSettings(velocity=m)) for m in ("shift", "raw", "inflate", "off")]
    cases.append(("shift, + 0.1 m/s noise", ProtocolSettings(noise_vel_mps=0.1)))
    for mode, settings in cases:
        vals = _runs(rec, "ekf", settings)
        print(f"| {mode} | {_cell(_col(vals, 'gnss', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'gnss', 'rms_vel_mps'), '.3f')} | "
              f"{_cell(_col(vals, 'outages', 'rms_pos_h_aided_m'))} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_rms_m'), '.0f')} |")


def noise_levels(rec):
    """Added position noise 1, 2, 3 m, with and without the velocities (ekf)."""
    print("\n### Added position noise (ekf, 10 seeds): horizontal RMS with GNSS throughout\n")
    print("| noise per axis (m) | raw fixes, horizontal RMS (m) | velocities shifted (m) | "
          "positions only (m) |")
    print("|---|---|---|---|")
    for sigma in (1.0, 2.0, 3.0):
        cells = [_cell(_col(_runs(rec, "ekf", ProtocolSettings(noise_pos_m=sigma,
                                                                 velocity=mode)),
                            "gnss", "rms_pos_h_m")) for mode in ("shift", "off")]
        print(f"| {sigma:g} | {sigma * np.sqrt(2):.2f} | {cells[0]} | {cells[1]} |")


def _elapsed(v, after_s):
    """Horizontal error ``after_s`` into each complete outage (nearest reference epoch)."""
    run = v.runs["outages"]
    h = horizontal(run.errors)
    out = []
    for d in run.drifts:
        if d.complete:
            k = np.argmin(np.abs(run.errors.time_s - (d.start_s + after_s)))
            out.append(h[k])
    return out


def phase_sweep(rec):
    """Outages at other phases of the drive, pooled: more outages than the default two."""
    print("\n### Outage phase sweep (seed 0; first outage 60, 80, ..., 300 s after the start)\n")
    print("| velocities | outages | error after 10 s (median) | after 30 s (median) | "
          "drift at end: median | RMS | min | max |")
    print("|---|---|---|---|---|---|---|---|")
    for mode, nhc in (("shift", 0.0), ("off", 0.0), ("shift", 0.3)):
        e10, e30, end = [], [], []
        for first in range(60, 301, 20):
            v = validate(rec, "ekf", ProtocolSettings(first_outage_s=float(first),
                                                      velocity=mode, nhc_sigma_mps=nhc), 0)
            e10 += _elapsed(v, 10.0)
            e30 += _elapsed(v, 30.0)
            end += [d.drift_h_m for d in v.runs["outages"].drifts if d.complete]
        end = np.array(end)
        print(f"| {mode}{', constraints 0.3 m/s' if nhc else ''} | {end.size} | {np.median(e10):.1f} m | {np.median(e30):.1f} m | "
              f"{np.median(end):.0f} m | {np.sqrt(np.mean(end**2)):.0f} m | "
              f"{end.min():.0f} m | {end.max():.0f} m |")


def consistency(rec):
    """Why the angle random walk is inflated: innovation consistency with GNSS throughout."""
    print("\n### Consistency against the ARW inflation (ekf, seed 0)\n")
    print("| ARW assumed (°/√h) | NIS per innovation row, GNSS throughout | "
          "position rows | velocity rows | largest gyro-bias estimate (°/h) | drift RMS (m) |")
    print("|---|---|---|---|---|---|")
    for factor in (1.0, 3.0, 10.0, 30.0):
        mems = replace(CONSUMER_MEMS, arw_inflation=factor)
        v = validate(rec, "ekf", ProtocolSettings(), 0, mems=mems)
        res = v.runs["gnss"].result
        ev = res.events["gnss"]
        acc = ev.accepted
        z2 = np.nanmean(ev.residual[acc] ** 2 / ev.S_diag[acc], axis=0)
        bg = np.degrees(np.abs(res.gyro_bias).max()) * 3600.0
        arw = factor * CONSUMER_MEMS.gyro_noise_dps_psqrthz * 60.0
        print(f"| {arw:.2f} (×{factor:g}) | {np.nanmean(z2):.2f} | {z2[:3].mean():.2f} | "
              f"{z2[3:].mean():.2f} | {bg:.0f} | "
              f"{v.runs['outages'].metrics['drift_h_rms_m']:.0f} |")


def ideal_start(rec, rest=(198.5, 205.5), span_s=59.0):
    """Free inertial navigation from the best start the data allow: a stop.

    Level and gyro bias from the stop itself (mean specific force and rate), heading and
    position from an RTK-aided run; then no aiding at all.  What this drifts is the IMU's
    own floor under any filter tuning.
    """
    v = validate(rec, "ekf", ProtocolSettings(noise_pos_m=0.0, outage_duration_s=0.0), 0)
    res = v.runs["gnss"].result
    imu, ref = rec.imu, rec.reference
    pitch, roll, f, w = coarse_align.level(imu, *rest)
    heading = res.att[np.searchsorted(res.time_s, rest[1]), 2]
    att = np.array([pitch, roll, heading])
    C = attitude.euler_to_dcm(att)
    lla = np.array([np.interp(rest[1], ref.time_s, ref.z[:, i]) for i in range(3)])
    bg = w - C.T @ earth.omega_ie_n(lla[0])
    ba = f - C.T @ np.array([0.0, 0.0, earth.gravity(lla[0], lla[2])])
    k0 = np.searchsorted(imu.time_s, rest[1] - 1e-9)
    k1 = np.searchsorted(imu.time_s, rest[1] + span_s)
    t = imu.time_s[k0:k1 + 1]
    h = np.diff(t)[:, None]
    free = ImuData(time_s=t, dtheta_b=imu.dtheta_b[k0:k1] - bg * h, dv_b=imu.dv_b[k0:k1] - ba * h)
    r = run_filter(free, {}, InitialState(float(t[0]), lla, np.zeros(3),
                                          attitude.euler_to_quat(att)), FilterConfig())
    err = errors_against(r, ref, rec.gnss.meta["lever_arm_b"])
    hz = horizontal(err)
    at = [hz[np.argmin(np.abs(err.time_s - rest[1] - s))] for s in (10.0, 30.0, span_s)]
    print(f"\n### Free inertial navigation from the stop at {rest[0]}-{rest[1]} s\n")
    print(f"Gyro bias at the stop {np.round(np.degrees(bg) * 3600.0, 0)} °/h (IMU turn-on "
          f"bias included), accelerometer {np.round(ba / 9.80665e-3, 1)} mg.  Horizontal "
          f"error after 10 s: {at[0]:.1f} m, 30 s: {at[1]:.1f} m, {span_s:.0f} s: {at[2]:.0f} m.")


def prior_sensitivity(rec):
    """The bias priors and random walks, one at a time (ekf, seed 0, default outages)."""
    print("\n### Bias priors and random walks (ekf, seed 0)\n")
    print("| change from CONSUMER_MEMS | horizontal RMS, GNSS throughout (m) | drift RMS (m) |")
    print("|---|---|---|")
    cases = [("none", {}), ("gyro bias prior 200 °/h", {"gyro_bias_sigma_dph": 200.0}),
             ("gyro bias walk 5 °/h/√h", {"gyro_bias_rw_dph_psh": 5.0}),
             ("gyro bias walk 20 °/h/√h", {"gyro_bias_rw_dph_psh": 20.0}),
             ("accelerometer bias prior 5 mg", {"accel_bias_sigma_ug": 5000.0}),
             ("accelerometer walk 30 µg/√s", {"accel_bias_rw_ug_psqrts": 30.0}),
             ("accelerometer walk 300 µg/√s", {"accel_bias_rw_ug_psqrts": 300.0})]
    for label, kw in cases:
        v = validate(rec, "ekf", ProtocolSettings(), 0, mems=replace(CONSUMER_MEMS, **kw))
        print(f"| {label} | {v.runs['gnss'].metrics['rms_pos_h_m']:.2f} | "
              f"{v.runs['outages'].metrics['drift_h_rms_m']:.0f} |")


def rest_biases(rec, stops=((1.5, 20.0), (198.5, 205.5), (262.0, 264.5), (528.5, 545.5))):
    """Mean gyro rate at each stop (the in-run bias change of the consumer gyro)."""
    print("\n### Mean gyro rate at the stops (IMU axes through the mounting, °/h)\n")
    print("| stop (s) | x | y | z |")
    print("|---|---|---|---|")
    for a, b in stops:
        sel = (rec.imu.time_s[:-1] >= a) & (rec.imu.time_s[1:] <= b)
        w = rec.imu.dtheta_b[sel].sum(0) / np.diff(rec.imu.time_s)[sel].sum()
        print(f"| {a:g}-{b:g} | " + " | ".join(f"{np.degrees(x) * 3600:.0f}" for x in w) + " |")


def timing_and_mounting(directory):
    """IMU delay and mounting: how much do they matter (ekf, 5 seeds)."""
    print("\n### IMU delay and mounting (ekf, 5 seeds)\n")
    print("| loader setting | horizontal RMS, GNSS throughout (m) | drift RMS (m) |")
    print("|---|---|---|")
    cases = [("delay 0.21 s (default), mounting rtklib-drive", {}),
             ("delay 0.21 s, no mounting (IMU frame)", {"mounting": "none"}),
             ("delay 0.125 s (the source's)", {"imu_delay_s": 0.125}),
             ("delay 0.30 s", {"imu_delay_s": 0.30}),
             ("delay 0 s", {"imu_delay_s": 0.0})]
    for label, kw in cases:
        vals = _runs(_load(directory, **kw), "ekf", ProtocolSettings(), seeds=range(5))
        print(f"| {label} | {_cell(_col(vals, 'gnss', 'rms_pos_h_m'))} | "
              f"{_cell(_col(vals, 'outages', 'drift_h_rms_m'), '.0f')} |")


def main(argv):
    data = Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets"))
    directory = Path(argv[1]) if len(argv) > 1 else data / "rtklib-drive"
    if not directory.is_dir():
        sys.exit(f"recording not found: {directory} (set FUZZYNAV_DATA or pass the directory)")
    rec = _load(directory)
    filters_table(rec)
    filters_table(rec, "off")
    constraints_table(rec)
    velocity_modes(rec)
    noise_levels(rec)
    phase_sweep(rec)
    consistency(rec)
    prior_sensitivity(rec)
    rest_biases(rec)
    ideal_start(rec)
    timing_and_mounting(directory)
    for path in write_figures(validate(rec, "ekf", ProtocolSettings(), 0), rec,
                              ROOT / "docs" / "figures"):
        print(f"\nwrote {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv)
