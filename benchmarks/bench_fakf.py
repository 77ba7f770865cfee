"""Cost of the fuzzy adaptive filter against the EKF on the same data (issue 4: <= 1.3x).

Both filters run on one ``paper000`` log (755 s at 100 Hz, 1-Hz GPS, 5-Hz imaging
polarization): ``ekf`` and ``fakf`` with the paper's two controllers evaluated inside the
compiled loop at every GPS and polarization epoch.  Best of several runs each, one core.
Usage: ``python benchmarks/bench_fakf.py``.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav.experiment import perturbed_initial_state, setup_for  # noqa: E402
from fuzzynav.filters.runner import run_filter  # noqa: E402
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402


def best_time(log, name, repeat=7):
    setup = setup_for(log, name)
    init = perturbed_initial_state(log, setup)
    sensors = setup.sensors_for(log.sensors)

    def once():
        return run_filter(log.imu, sensors, init, setup.config, setup.adapters)

    once()  # compile / warm
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        once()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None):
    log = simulate(load_scenario("paper000"), 0, tempfile.mkdtemp())
    n = log.imu.n_samples
    epochs = sum(d.time_s.size for d in log.sensors.values())
    t_ekf, t_fakf = best_time(log, "ekf"), best_time(log, "fakf")
    text = "\n".join([
        "## Fuzzy adaptive filter against the EKF (`benchmarks/bench_fakf.py`)", "",
        f"`paper000`, seed 0: {n} IMU samples, {epochs} measurement epochs (1-Hz GPS, 5-Hz "
        f"imaging polarization), one core, best of 7. Machine: {machine()}.", "",
        "| filter | run time (ms) | IMU samples/s | relative |", "|---|---|---|---|",
        f"| ekf | {t_ekf * 1e3:.1f} | {n / t_ekf:,.0f} | 1.00 |",
        f"| fakf (paper rules, both controllers) | {t_fakf * 1e3:.1f} | {n / t_fakf:,.0f} | "
        f"{t_fakf / t_ekf:.2f} |", "",
        "Goal of issue 4: a FAKF run costs at most 1.3x an EKF run. The fuzzy systems run in "
        "their compiled form inside the loop (no Python call per epoch)."])
    print(text)
    if "--no-write" not in (argv or sys.argv[1:]):
        write_section("fakf", text)


if __name__ == "__main__":
    main()
