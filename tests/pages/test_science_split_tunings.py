"""The car drive's held-out half over several tunings, on hand-made frames."""
import numpy as np
import pandas as pd
import pytest

from fuzzynav.metrics import crossed_ci
from fuzzynav.pages import science_split_tunings as st

METRICS = ("rms_pos_m", "rms_vel_mps")


def _frame(design_pos, seeds=(100, 101, 102)):
    rows = []
    for seed, p in zip(seeds, design_pos):
        rows.append({"scenario": "half", "seed": seed, "filter": st.REF, "rms_pos_m": 2.0,
                     "rms_vel_mps": 0.5})
        rows.append({"scenario": "half", "seed": seed, "filter": st.DESIGN, "rms_pos_m": p,
                     "rms_vel_mps": 0.5})
        rows.append({"scenario": "half", "seed": seed, "filter": "ekf", "rms_pos_m": 9.0,
                     "rms_vel_mps": 9.0})
    return pd.DataFrame(rows)


def test_differences_are_the_objective_against_the_same_tunings_reference():
    # score = mean of the pos and vel ratios: (p/2 + 1)/2, so the difference is p/4 - 1/2
    d = st.differences([_frame([1.0, 2.0, 3.0]), _frame([2.0, 2.0, 2.0])], METRICS)
    assert d.shape == (2, 3)
    np.testing.assert_allclose(d, [[-0.25, 0.0, 0.25], [0.0, 0.0, 0.0]], atol=1e-15)


def test_tunings_on_other_seeds_refused():
    with pytest.raises(ValueError, match="different seeds"):
        st.differences([_frame([1.0] * 3), _frame([1.0] * 3, seeds=(1, 2, 3))], METRICS)


def test_lines_give_each_tuning_and_the_crossed_pool():
    frames = [_frame([1.6, 1.7, 1.5]), _frame([1.9, 2.1, 1.8]), _frame([1.7, 1.9, 1.6])]
    text = "\n".join(st.tunings_lines(frames, METRICS, "noise seeds"))
    assert text.count("\n| ") == 5  # header rule excluded: 3 tunings, pooled, header
    pooled = crossed_ci(st.differences(frames, METRICS))
    assert f"| pooled | {pooled.mean:+.3f} [{pooled.lo:+.3f}, {pooled.hi:+.3f}]" in text
    assert "| 0 | -0.100 [" in text  # mean p 1.6: 1.6/4 - 1/2
