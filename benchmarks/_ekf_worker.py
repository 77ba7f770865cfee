"""Worker of ``bench_ekf.py``: times filter runs of whichever fuzzynav is first on sys.path.

Started by ``bench_ekf.py`` once per revision (``PYTHONPATH`` selects the source tree) and
kept alive, so the two revisions are timed in alternation within one run.  Protocol on
stdin/stdout, one JSON document per line: the worker answers ``{"ready": ...}`` after
loading the data and compiling, then for each request ``{"case": name, "repeat": k}`` the
``k`` wall and CPU times [s]; ``{"profile": 1}`` answers ``profile_ekf.profile()``;
``{"dump": name, "path": p}`` saves that case's solution and
event log to ``p`` (for the agreement check); ``{"quit": 1}`` ends it.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the benchmarks' own modules


def _fuzzy_call_case():
    """One compiled fuzzy evaluation (``bench_fuzzy``'s system) in a numba loop, 10 000 x."""
    import bench_fuzzy as bz  # noqa: E402  (same directory, on sys.path)

    cf = bz.issue_system().compile()
    X = np.random.default_rng(2026).uniform(-1.0, 1.0, (10_000, 2))
    y, work = np.empty(cf.n_outputs), np.empty(cf.work_size)
    return lambda: bz._loop(cf.fparams, cf.iparams, X, y, work)


def _filter_cases(cache_dir):
    # names both trees have (modules were renamed since older base revisions)
    from fuzzynav.experiment import perturbed_initial_state, setup_for, simulate
    from fuzzynav.filters.runner import run_filter
    from fuzzynav.sim.scenario import load_scenario

    log = simulate(load_scenario("paper000"), 0, cache_dir)
    cases = {}
    for name in ("ekf", "fakf"):
        setup = setup_for(log, name)
        init = perturbed_initial_state(log, setup)
        sensors = setup.sensors_for(log.sensors)
        cases[name] = (lambda s=setup, i=init, se=sensors: run_filter(
            log.imu, se, i, s.config, s.adapters, s.sensor_options))
    return cases


def _gnss_ins_case(minutes):
    import bench_filter as bf  # noqa: E402  (same directory, on sys.path)

    from fuzzynav.filters.runner import run_filter

    _, imu, gnss, init = bf.make_data(minutes)
    cfg = bf.CONFIG.with_(out_rate_hz=1.0)
    return lambda: run_filter(imu, {"gnss": gnss}, init, cfg)


def _dump(result, path):
    ev = {f"ev_{k}_{f}": getattr(v, f) for k, v in result.events.items()
          for f in ("residual", "S_diag", "nis", "flag")}
    np.savez(path, lla=result.lla, vel_n=result.vel_n, q_bn=result.q_bn,
             sigma=result.sigma, xs=result.sensor_states, **ev)


def main():
    cache_dir, minutes = sys.argv[1], float(sys.argv[2])
    import fuzzynav

    cases = _filter_cases(cache_dir)
    cases["gnss-ins"] = _gnss_ins_case(minutes)
    cases["fuzzy-call"] = _fuzzy_call_case()
    for fn in cases.values():
        fn()  # compile or load the kernels, warm the caches
    print(json.dumps({"ready": fuzzynav.__file__}), flush=True)
    for line in sys.stdin:
        req = json.loads(line)
        if "quit" in req:
            break
        if "profile" in req:
            import profile_ekf  # noqa: E402  (same directory, on sys.path)

            print(json.dumps(profile_ekf.profile(cache_dir)), flush=True)
            continue
        if "dump" in req:
            _dump(cases[req["dump"]](), req["path"])
            print(json.dumps({"ok": 1}), flush=True)
            continue
        fn, wall, cpu = cases[req["case"]], [], []
        for _ in range(int(req["repeat"])):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        print(json.dumps({"wall": wall, "cpu": cpu}), flush=True)


if __name__ == "__main__":
    main()
