"""Are the tuned rule files' regression checks portable?  Their ``expected`` metrics are
compared to 1e-6 (or to a file's own ``rtol``), but another CPU or library build changes the
last bits of the arithmetic; a closed loop that amplifies rounding turns that into metrics
that differ by percent (``paper000_rscale_tuned_t2.json``: 8 % on the 3-D position RMS).

Here each expected block is re-run with its IMU velocity increments perturbed by 2e-16
relative (what another build does, at most), and the spread of its metrics must stay within
the file's tolerance: a file that fails needs the wider ``rtol`` and its ``rtol_reason``
(measured as in that file).  The default run checks a well-conditioned tuning and the
ill-conditioned one; ``pytest -m slow`` checks every file.
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from fuzzynav.experiment import run_on_log
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import simulate
from tests.test_rules_regression import RTOL, ROOT, rule_files_with_expected

#: relative size of the perturbation of every velocity increment
ULP_NOISE = 2e-16


def _spread(path, runs: int) -> dict:
    """Largest relative deviation of each expected metric from the unperturbed run's, over
    ``runs`` perturbed runs."""
    exp = json.loads(path.read_text(encoding="utf-8"))["expected"]
    files = [str(path)] + [str(path.parent / n) for n in exp.get("with_rules", [])]
    log = simulate(load_scenario(exp["scenario"]), int(exp["seed"]), None)
    opts = {"rules": files}
    kw = {"t_start_s": float(exp.get("t_start_s", 0.0))}
    base = run_on_log(log, exp.get("filter", "fakf"), opts, **kw).metrics
    rng = np.random.default_rng(0)
    worst = dict.fromkeys(exp["metrics"], 0.0)
    for _ in range(runs):
        dv = log.imu.dv_b * (1.0 + ULP_NOISE * rng.standard_normal(log.imu.dv_b.shape))
        moved = dataclasses.replace(log, imu=dataclasses.replace(log.imu, dv_b=dv))
        m = run_on_log(moved, exp.get("filter", "fakf"), opts, **kw).metrics
        for k in worst:
            worst[k] = max(worst[k], abs(m[k] / base[k] - 1.0))
    return worst, float(exp.get("rtol", RTOL))


def _check(name: str, runs: int) -> dict:
    worst, rtol = _spread(ROOT / "rules" / name, runs)
    bad = {k: v for k, v in worst.items() if v > rtol}
    assert not bad, f"{name}: metrics move by more than rtol {rtol:g} under {ULP_NOISE:g} " \
                    f"rounding changes: {bad}"
    return worst


def test_a_well_conditioned_tuning_moves_far_below_its_tolerance():
    worst = _check("paper000_rscale_tuned_t1.json", runs=2)
    assert max(worst.values()) < 1e-9, worst


def test_the_ill_conditioned_tuning_is_compared_within_what_rounding_moves():
    worst = _check("paper000_rscale_tuned_t2.json", runs=3)
    # it really is ill-conditioned: the 1e-6 of a plain file would fail on other builds
    assert max(worst.values()) > 1e-4, worst


@pytest.mark.slow
@pytest.mark.parametrize("path", rule_files_with_expected(), ids=lambda p: p.name)
def test_every_expected_block_tolerates_rounding_changes(path):
    _check(path.name, runs=4)
