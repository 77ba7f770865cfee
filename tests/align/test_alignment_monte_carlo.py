"""The alignment's Monte-Carlo goes through the package's one (:func:`experiment.monte_carlo`)
and its metric, the azimuth alignment time, is the definition's."""
import dataclasses

import numpy as np
import pytest

from fuzzynav.align import alignment_run as R
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import monte_carlo


def test_alignment_time_is_the_first_time_the_error_stays_inside():
    t = np.arange(6.0)
    thr = 1.0
    # outside at 0, 1 and 3, inside from 4 on: aligned at t = 4
    assert R.alignment_time(t, np.array([5.0, -2.0, 0.5, 1.5, -0.2, 0.9]), thr) == 4.0
    assert R.alignment_time(t, np.zeros(6), thr) == 0.0            # inside throughout
    assert np.isnan(R.alignment_time(t, np.array([0, 0, 0, 0, 0, 3.0]), thr))  # never


def _short():
    scn = load_alignment_scenario("paper002")
    return dataclasses.replace(scn, duration_s=60.0, threshold_arcmin=120.0,
                               imu=dataclasses.replace(scn.imu, rate_hz=10.0))


def test_each_row_is_that_filters_run_on_that_seed():
    scn = _short()
    df = monte_carlo(scn, ["align-kf", "align-fuzzy"], [3, 4], seed_runs=R.seed_runs(scn))
    assert list(zip(df["filter"], df["seed"])) == [("align-kf", 3), ("align-fuzzy", 3),
                                                   ("align-kf", 4), ("align-fuzzy", 4)]
    assert set(df["scenario"]) == {scn.name}
    for row in df.to_dict("records"):
        log = R.simulate(scn, row["seed"])
        run = R.run_align_filter(row["filter"], scn, log, R.epochs(scn, log, row["seed"]))
        for key, value in R.metrics(run, scn.threshold_arcmin).items():
            assert row[key] == value, key
    # the two filters saw the same log: their errors differ (the scaling acts), the seeds too
    assert df["final_azimuth_arcmin"].nunique() == 4


def test_options_of_navigation_runs_are_refused_with_seed_runs():
    scn = _short()
    with pytest.raises(FuzzynavError, match="cache_dir, t_start_s apply to navigation"):
        monte_carlo(scn, ["align-kf"], [0], cache_dir="x", t_start_s=5.0,
                    seed_runs=R.seed_runs(scn))
