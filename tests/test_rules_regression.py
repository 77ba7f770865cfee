"""Regression tests of tuned rules: every rule file in ``rules/`` with an ``expected`` block is
re-run (``fakf`` with the file and its ``with_rules`` companions, on its scenario and seed) and
must reproduce its metrics to 1e-6, or to the file's own ``rtol`` when its block gives one with
an ``rtol_reason`` (a controller whose recursion amplifies float rounding between kernel
revisions and CPUs).  The mechanism itself is also run on a rule file exported from a
tiny study into a temporary directory, so this test never only skips."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from fuzzynav.experiment import run_on_log
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
RTOL = 1e-6
EXPORTED = "exported-in-a-temp-dir"


def rule_files_with_expected() -> list:
    out = []
    for path in sorted((ROOT / "rules").glob("*.json")):
        doc = json.loads(path.read_text(encoding="utf-8"))
        # alignment rule files are re-run by tests/align/test_tuned_rules.py
        if "expected" in doc and doc["expected"].get("kind") != "alignment":
            out.append(path)
    return out


def check_expected(path: Path, cache_dir) -> dict:
    """Re-run what a rule file's ``expected`` block describes; compare; the metrics."""
    exp = json.loads(path.read_text(encoding="utf-8"))["expected"]
    files = [path] + [path.parent / name for name in exp.get("with_rules", [])]
    log = simulate(load_scenario(exp["scenario"]), int(exp["seed"]), cache_dir)
    out = run_on_log(log, exp.get("filter", "fakf"), {"rules": [str(f) for f in files]},
                     t_start_s=float(exp.get("t_start_s", 0.0)))
    assert out.result.ok, out.result.status
    assert exp["metrics"], "an expected block without metrics checks nothing"
    rtol = float(exp.get("rtol", RTOL))
    assert rtol == RTOL or exp.get("rtol_reason"), f"{path.name}: an rtol needs its rtol_reason"
    for key, value in exp["metrics"].items():
        assert out.metrics[key] == pytest.approx(value, rel=rtol), (path.name, key)
    return out.metrics


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("regression-cache")


@pytest.mark.parametrize("case", rule_files_with_expected() + [EXPORTED],
                         ids=lambda c: c if isinstance(c, str) else c.name)
def test_rule_files_reproduce_their_expected_metrics(case, cache, tmp_path):
    if case == EXPORTED:
        from fuzzynav.tuning.export import export_rules
        from tests.tuning.studies import ATT_CONTROLLER, BASE, finished_study

        cfg, study = finished_study(tmp_path, cache, trials=3, controllers=[
            BASE["controllers"][0], ATT_CONTROLLER])
        paths = export_rules(cfg, study, tmp_path / "rules" / "tuned.json", cache_dir=cache)
        assert len(paths) == 2
        metrics = [check_expected(p, cache) for p in paths]
        # one fakf run with both files, recorded in both; re-run with the files listed in the
        # other order, so two configurations: the same metrics up to rounding
        assert metrics[1] == pytest.approx(metrics[0], rel=1e-12, abs=0.0, nan_ok=True)
    else:
        check_expected(case, cache)
