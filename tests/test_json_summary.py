"""The JSON every table writes: mean with a Student-t 95 % CI, and NaN as null."""
import json
import math

import numpy as np
import pytest
from scipy import stats

from fuzzynav.fileio import json_ready
from fuzzynav.metrics import summary_json


def test_summary_is_the_mean_and_t_interval():
    x = [1.0, 2.0, 4.0, 7.0]
    out = summary_json(x)
    lo, hi = stats.t.interval(0.95, len(x) - 1, loc=np.mean(x), scale=stats.sem(x))
    assert out["mean"] == pytest.approx(3.5, rel=1e-15)
    assert out["ci95"] == pytest.approx([lo, hi], rel=1e-12)
    assert out["values"] == x


def test_non_finite_values_are_left_out_of_the_mean_and_written_as_null():
    out = summary_json([2.0, math.nan, 4.0])
    assert out["mean"] == pytest.approx(3.0, rel=1e-15)
    doc = json.loads(json.dumps(json_ready({"m": out, "t": (math.inf, 1)}), allow_nan=False))
    assert doc["m"]["values"] == [2.0, None, 4.0] and doc["t"] == [None, 1]
