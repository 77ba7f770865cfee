"""Figures of docs/polarization.md: sun accuracy, polarization-compass accuracy, kernel speed.

Run by hand: ``python benchmarks/polarization_accuracy.py`` (about a minute; needs pvlib).
Prints markdown tables; nothing is asserted (the tests do that).
"""
from __future__ import annotations

import time

import numpy as np

from fuzzynav.nav.attitude import euler_to_dcm
from fuzzynav.nav import polarization_solver as ps
from fuzzynav.sim import skylight as sk
from fuzzynav.sim import sun

SIGMA_AOP_DEG = 0.3


def sun_vs_spa():
    """Largest elevation / azimuth*cos(elevation) differences to SPA per year [deg]."""
    import pandas as pd
    import pvlib

    print("| year | max elevation error | max azimuth error x cos(el) | max EoT error |")
    print("|---|---|---|---|")
    rng = np.random.default_rng(0)
    for year in (1900, 1950, 2000, 2024, 2050, 2100):
        times = pd.date_range(f"{year}-01-01", f"{year + 1}-01-01", freq="37min", tz="UTC")
        jd = sun.julian_day(times.tz_convert(None).to_numpy())
        e_el = e_az = e_eot = 0.0
        for lat in (-75.0, -40.0, 0.0, 23.44, 38.0, 60.0, 75.0):
            lon = rng.uniform(-180.0, 180.0)
            ref = pvlib.solarposition.get_solarposition(times, lat, lon, delta_t=None)
            mine = sun.sun_position(jd, np.radians(lat), np.radians(lon))
            el = np.degrees(mine.elevation_rad)
            d_az = (np.degrees(mine.azimuth_rad) - ref["azimuth"].to_numpy() + 180) % 360 - 180
            e_el = max(e_el, np.abs(el - ref["elevation"].to_numpy()).max())
            e_az = max(e_az, np.abs(d_az * np.cos(np.radians(el))).max())
            e_eot = max(e_eot, np.abs(mine.equation_of_time_s
                                      - 60 * ref["equation_of_time"].to_numpy()).max())
        print(f"| {year} | {e_el:.4f}° | {e_az:.4f}° | {e_eot:.2f} s |")


def _cases(n, tilt_deg, elev_deg, rng):
    for _ in range(n):
        direction = rng.uniform(0.0, 2 * np.pi)
        tau = np.radians(tilt_deg) * np.sqrt(rng.uniform())
        pitch, roll = tau * np.cos(direction), tau * np.sin(direction)
        heading, az = rng.uniform(0.0, 2 * np.pi, 2)
        el = np.radians(rng.uniform(*elev_deg))
        yield pitch, roll, heading, np.array([np.cos(el) * np.sin(az),
                                              np.cos(el) * np.cos(az), np.sin(el)])


def zenith_sensitivities():
    """Heading sigma from 0.3° AoP noise, and heading error per degree of tilt error."""
    rng = np.random.default_rng(1)
    print("| tilt up to | sun elevation | heading 1-sigma: median / 95 % | "
          "|dh/dtilt|: median / 95 % |")
    print("|---|---|---|---|")
    for tilt in (0.0, 5.0, 15.0, 30.0):
        for elev in ((5.0, 30.0), (30.0, 60.0), (60.0, 80.0)):
            sig, cpl = [], []
            for p, r, h, s in _cases(4000, tilt, elev, rng):
                aop = ps.zenith_aop(euler_to_dcm([p, r, h]), s)
                _, dh = ps.heading_from_zenith_aop(aop, s, p, r, h)
                dp, dr = ps.zenith_heading_tilt_partials(s, p, r, h)
                sig.append(abs(dh) * SIGMA_AOP_DEG)
                cpl.append(np.hypot(dp, dr))
            q = np.percentile(sig, [50, 95])
            c = np.percentile(cpl, [50, 95])
            print(f"| {tilt:g}° | {elev[0]:g}-{elev[1]:g}° | {q[0]:.2f}° / {q[1]:.2f}° | "
                  f"{c[0]:.2f} / {c[1]:.2f} |")


def imaging_accuracy():
    """Pitch and heading 1-sigma of the imaging solver, level vehicle, 0.3° per view."""
    print("| views | sun elevation | pitch 1-sigma (median / 95 %) | "
          "heading 1-sigma (median / 95 %) |")
    print("|---|---|---|---|")
    rng = np.random.default_rng(2)
    sig = np.radians(SIGMA_AOP_DEG)
    for ring in (30.0, 60.0):
        views = np.vstack([[0.0, 0.0, 1.0], sk.view_direction(
            np.radians(ring), np.radians(np.arange(6) * 60.0))])
        for elev in ((5.0, 30.0), (30.0, 60.0), (60.0, 80.0)):
            sp, sh = [], []
            for p, r, h, s in _cases(2000, 5.0, elev, rng):
                aops = sk.angle_of_polarization(views, euler_to_dcm([p, r, h]).T @ s)
                _, _, cov, _ = ps.imaging_pitch_heading(aops, views, s, r, p, h, 0.02, 0.5, sig)
                sp.append(np.degrees(np.sqrt(cov[0, 0])))
                sh.append(np.degrees(np.sqrt(cov[1, 1])))
            a, b = np.percentile(sp, [50, 95]), np.percentile(sh, [50, 95])
            print(f"| zenith + 6 at {ring:g}° | {elev[0]:g}-{elev[1]:g}° | "
                  f"{a[0]:.2f}° / {a[1]:.2f}° | {b[0]:.2f}° / {b[1]:.2f}° |")


def kernel_speed():
    """Microseconds per call of the kernels the filter uses."""
    s = np.array([0.3, 0.5, 0.81])
    s /= np.linalg.norm(s)
    C = euler_to_dcm([0.05, -0.03, 1.2])
    views = np.vstack([[0.0, 0.0, 1.0], sk.view_direction(np.radians(30.0),
                                                          np.radians(np.arange(6) * 60.0))])
    aops = sk.angle_of_polarization(views, C.T @ s)
    calls = {
        "zenith_aop": lambda: ps.zenith_aop(C, s),
        "heading_from_zenith_aop": lambda: ps.heading_from_zenith_aop(0.3, s, 0.05, -0.03, 1.2),
        "imaging_pitch_heading (7 views)": lambda: ps.imaging_pitch_heading(
            aops, views, s, -0.03, 0.05, 1.2, 0.02, 0.5, 0.005),
        "sun_vector_nb": lambda: sun.sun_vector_nb(2460000.5, 0.66, 1.96, 69.2),
    }
    print("| kernel | µs per call (from Python, includes call overhead) |")
    print("|---|---|")
    for name, f in calls.items():
        f()
        n = 20000
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        print(f"| {name} | {1e6 * (time.perf_counter() - t0) / n:.2f} |")


if __name__ == "__main__":
    sun_vs_spa()
    print()
    zenith_sensitivities()
    print()
    imaging_accuracy()
    print()
    kernel_speed()
