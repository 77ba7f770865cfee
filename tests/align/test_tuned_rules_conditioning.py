"""Are the tuned alignment rule files' regression checks portable?

``tests/align/test_tuned_rules.py`` compares each file's ``expected`` metrics to 1e-6; another
CPU or library build changes the last bits of the arithmetic.  As
``tests/test_rules_conditioning.py`` does for the navigation files, each expected block is
re-run with the IMU's velocity increments perturbed by 2e-16 relative (what another build
does, at most) and its metrics must move within the regression's own tolerance.  The
default run checks one file; ``pytest -m slow`` checks every one.
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from fuzzynav.align import alignment_run as R
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.fuzzy import load_fis
from tests.align.test_tuned_rules import RTOL, alignment_rule_files
from tests.test_rules_conditioning import ULP_NOISE

#: the regression's absolute tolerance (``pytest.approx(..., abs=1e-9)`` there)
ABS = 1e-9


def _excess(path, runs: int) -> dict:
    """Per metric, the largest deviation of a perturbed run from the unperturbed one as a
    multiple of the regression's tolerance (above 1: the regression would fail)."""
    exp = json.loads(path.read_text(encoding="utf-8"))["expected"]
    scn = load_alignment_scenario(exp["scenario"])
    seed, rules = int(exp["seed"]), load_fis(path)
    log = R.simulate(scn, seed)

    def metrics(lg):
        run = R.run_align_filter(exp["filter"], scn, lg, R.epochs(scn, lg, seed), rules=rules)
        return R.metrics(run, scn.threshold_arcmin)

    base = metrics(log)
    rng = np.random.default_rng(0)
    worst = dict.fromkeys(exp["metrics"], 0.0)
    for _ in range(runs):
        dv = log.imu.dv_b * (1.0 + ULP_NOISE * rng.standard_normal(log.imu.dv_b.shape))
        got = metrics(dataclasses.replace(log, imu=dataclasses.replace(log.imu, dv_b=dv)))
        for k in worst:
            tol = max(RTOL * abs(base[k]), ABS)
            worst[k] = max(worst[k], abs(got[k] - base[k]) / tol)
    return worst


FILES = alignment_rule_files()


def _check(path, runs: int) -> dict:
    worst = _excess(path, runs)
    bad = {k: v for k, v in worst.items() if v > 1.0}
    assert not bad, (f"{path.name}: metrics move by more than the regression's tolerance "
                     f"(times it) under {ULP_NOISE:g} rounding changes: {bad}")
    return worst


def test_an_alignment_tuning_moves_within_its_regression_tolerance():
    assert FILES, "no tuned alignment rule files"
    _check(FILES[0], runs=2)


@pytest.mark.slow
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_alignment_tuning_moves_within_its_regression_tolerance(path):
    _check(path, runs=6)
