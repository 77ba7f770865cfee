"""Behaviour lock: every named filter on every source, metrics written as exact JSON.

Run before and after a refactoring that must not change results, then compare the two
files byte for byte (``--compare``).  Floats are written by ``repr`` (``json``), so a
difference in the last bit shows.  What a filter refuses on a source (a missing sensor,
say) is recorded as its error class and message, so refusals are locked too.

Sources (``--quick``: the first seed, paper000, A-KIT 1, one study window):

* simulated scenarios ``paper000``, ``paper001``, ``paper003``, ``paper004``, seeds 0-2;
* the alignment filters on ``paper002`` (seeds 0-2) and the alignment chain
  ``align-kf -> ekf`` on ``paper000`` (seed 0);
* the car drive (rtklib-drive) under the default validation protocol, seed 0, both feeds;
* A-KIT trajectories 1-8;
* study runs on recordings (``akit:akit:3@0-50%``, ``rtklib:rtklib-drive@50-100%``);
* the ALS baseline's fitted multipliers on paper000 seed 0.

The recordings are looked up like the package does (``fuzzynav data fetch``, then
``$FUZZYNAV_DATA``, then ``../shared/datasets``); absent ones are skipped and named in
the output's ``skipped`` list.

Usage::

    python tools/behaviour_lock.py --out before.json [--quick] [--only paper000,akit]
    python tools/behaviour_lock.py --compare before.json after.json
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

SCENARIOS = ("paper000", "paper001", "paper003", "paper004")
SEEDS = (0, 1, 2)
STUDY_RUNS = ("akit:akit:3@0-50%", "rtklib:rtklib-drive@50-100%")


def _filters():
    from fuzzynav.filters.named import list_filters

    return [f.name for f in list_filters()]


def _clean(metrics: dict) -> dict:
    """Metrics as JSON-exact values (NaN and infinities as strings: JSON has neither)."""
    out = {}
    for k, v in sorted(metrics.items()):
        v = float(v)
        out[k] = v if math.isfinite(v) else repr(v)
    return out


#: the checkout's root: error messages name files under it, which differ between worktrees
ROOT = str(Path(__file__).resolve().parents[1])


def _error(exc) -> dict:
    """A refusal as behaviour to lock: its class and message (checkout root as ``<repo>``)."""
    return {"error": f"{type(exc).__name__}: {str(exc).replace(ROOT, '<repo>')[:200]}"}


def _guard(fn):
    """``fn()``'s metrics, or the error it raised (:func:`_error`)."""
    try:
        return _clean(fn())
    except Exception as exc:  # noqa: BLE001 - a refusal is behaviour to lock as well
        return _error(exc)


def simulated(out, seeds, scenarios):
    from fuzzynav.experiment import run_on_log
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario

    for name in scenarios:
        scn = load_scenario(name)
        for seed in seeds:
            log = simulate(scn, seed)
            for f in _filters():
                out[f"{name}/{seed}/{f}"] = _guard(lambda: run_on_log(log, f).metrics)


def alignment(out, seeds):
    from fuzzynav.align.chain import run_aligned
    from fuzzynav.align.alignment_run import ALIGN_FILTERS, seed_runs
    from fuzzynav.experiment import monte_carlo
    from fuzzynav.align.scenario import load_alignment_scenario
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario

    scn = load_alignment_scenario("paper002")
    df = monte_carlo(scn, list(ALIGN_FILTERS), seeds, seed_runs=seed_runs(scn))
    for row in df.to_dict("records"):
        f, seed = row.pop("filter"), row.pop("seed")
        row.pop("scenario")
        out[f"paper002/{seed}/{f}"] = _clean(row)
    log = simulate(load_scenario("paper000"), 0)
    out["chain/paper000/0/align-kf->ekf"] = _guard(lambda: run_aligned(log, "ekf").metrics)


def car_drive(out, skipped):
    from fuzzynav.realdata.protocol import ProtocolSettings
    from fuzzynav.realdata.sources import parse_data_spec
    from fuzzynav.realdata.validate import validate

    try:
        source, directory, session = parse_data_spec("rtklib-drive")
        rec = source.load(directory, session=session)
    except Exception as exc:  # noqa: BLE001
        skipped.append(f"rtklib-drive: {exc}")
        return
    for f in _filters():
        try:
            v = validate(rec, f, ProtocolSettings(), 0)
        except Exception as exc:  # noqa: BLE001
            out[f"car/0/{f}"] = _error(exc)
            continue
        for feed, run in v.runs.items():
            out[f"car/0/{f}/{feed}"] = _clean(run.metrics)


def akit(out, skipped, trajectories):
    from fuzzynav.realdata.akit import run_trajectory
    from fuzzynav.realdata.sources import parse_data_spec

    try:
        source, directory, _ = parse_data_spec(f"akit:{trajectories}")
        recs = source.load(directory, session=trajectories)
    except Exception as exc:  # noqa: BLE001
        skipped.append(f"akit: {exc}")
        return
    for rec in recs:
        for f in _filters():
            out[f"akit/{rec.trajectory}/{f}"] = _guard(lambda: run_trajectory(rec, f)[1])


def study_runs(out, skipped, names, filters=("ekf", "fuzzy", "sage-husa-tuned")):
    from fuzzynav.experiment import run_on_log
    from fuzzynav.realdata.studyruns import recording_run

    for name in names:
        try:
            run = recording_run(name, 0)
        except Exception as exc:  # noqa: BLE001
            skipped.append(f"{name}: {exc}")
            continue
        for f in filters:
            out[f"study/{name}/{f}"] = _guard(lambda: run_on_log(run, f).metrics)


def als(out):
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario
    from fuzzynav.tuning.als_fit import run_scales

    out["als/paper000/0"] = _guard(lambda: run_scales(simulate(load_scenario("paper000"), 0)))


PARTS = ("sim", "align", "car", "akit", "study", "als")


def collect(quick: bool, only) -> dict:
    out, skipped, took = {}, [], {}
    seeds = SEEDS[:1] if quick else SEEDS
    steps = {"sim": lambda: simulated(out, seeds, SCENARIOS[:1] if quick else SCENARIOS),
             "align": lambda: alignment(out, seeds),
             "car": lambda: car_drive(out, skipped),
             "akit": lambda: akit(out, skipped, "1" if quick else "1-8"),
             "study": lambda: study_runs(out, skipped, STUDY_RUNS[:1] if quick else STUDY_RUNS),
             "als": lambda: als(out)}
    for part in only or PARTS:
        t0 = time.perf_counter()
        steps[part]()
        took[part] = round(time.perf_counter() - t0, 1)
        print(f"{part}: {took[part]} s", file=sys.stderr)
    return {"results": out, "skipped": skipped, "quick": quick, "parts": list(only or PARTS)}


def compare(a: Path, b: Path) -> int:
    ra, rb = (json.loads(p.read_text())["results"] for p in (a, b))
    diff = [k for k in sorted(set(ra) | set(rb)) if ra.get(k) != rb.get(k)]
    for k in diff[:40]:
        print(f"{k}:\n  {a.name}: {ra.get(k)}\n  {b.name}: {rb.get(k)}")
    print(f"{len(diff)} of {len(set(ra) | set(rb))} entries differ")
    return 1 if diff else 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--only", type=lambda s: s.split(","), help=f"parts: {','.join(PARTS)}")
    p.add_argument("--compare", nargs=2, type=Path, metavar=("A", "B"))
    args = p.parse_args(argv)
    if args.compare:
        return compare(*args.compare)
    if args.out is None:
        p.error("--out FILE or --compare A B")
    data = collect(args.quick, args.only)
    tmp = args.out.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
    tmp.replace(args.out)
    print(f"wrote {args.out}: {len(data['results'])} entries; skipped {data['skipped']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
