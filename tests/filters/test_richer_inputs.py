"""Richer fuzzy inputs (NIS, innovation trend) and the process-noise output (rq-scaling)."""
import json
import math

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import window
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.adaptation.rq_scaling import FuzzyRQScaling, Q_MAX
from fuzzynav.fuzzy import load_fis

RQ = "rules/paper000_rq_gnss.json"
GNSS = measurements.get("gnss")


def test_nis_is_the_mean_normalised_square_of_the_channel_rows():
    r = np.array([1.0, 2.0, 3.0])
    HPH = np.diag([1.0, 1.0, 2.0])
    R = np.ones(3)
    chan = np.array([0, 0, 1], np.int64)
    st = np.zeros(window.window_size(4, 2))
    # channel 0: (1/2 + 4/2) / 2; all rows: (1/2 + 4/2 + 9/3) / 3
    assert window.statistic_of(2, st, 0, 4, 2, HPH, R, chan, 3, 0, r) == pytest.approx(1.25)
    assert window.statistic_of(2, st, 0, 4, 2, HPH, R, chan, 3, -1, r) == \
        pytest.approx(5.5 / 3)


def test_trend_compares_the_newer_and_older_half_of_the_window():
    n, c = 4, 2
    st = np.zeros(window.window_size(n, c))
    chan = np.array([0], np.int64)
    for a in (3.0, 3.0, 1.0, 1.0, 2.0, 2.0):  # squared sums 9 9 1 1 4 4; kept: 1 1 4 4
        window.push(st, 0, n, c, np.array([a]), chan, 1)
    HPH, R = np.diag([1.5]), np.array([0.5])  # tr P_z = 2
    # (mean(4, 4) - mean(1, 1)) / 2 = 1.5
    got = window.statistic_of(3, st, 0, n, c, HPH, R, chan, 1, 0, np.array([2.0]))
    assert got == pytest.approx(1.5)


def test_a_q_scale_output_needs_the_rq_adapter(tmp_path):
    b = Binding.of(load_fis(RQ), RQ)
    assert {o.target for o in b.outputs} == {"r_scale", "q_scale"}
    doc = json.loads(open(RQ).read())
    doc["binding"]["adapter"] = "r-scaling"  # R-scaling alone has no process-noise output
    p = tmp_path / "r_only.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(InputFileError, match=r"outputs\.q.*unknown target 'q_scale'"):
        Binding.of(load_fis(p), str(p))


def _drive(policy, rr, n=40):
    """Kernel outputs over ``n`` epochs whose residuals grow by ``rr`` per epoch."""
    bound = policy.bind(GNSS)
    fns, _ = adaptation.kernel_table()
    chan = np.array([0, 0, 0, 1, 1, 1], np.int64)
    qprod, outs = 1.0, []
    for k in range(n):
        out, diag = np.zeros(8), np.zeros(adaptation.N_DIAG)
        r = np.full(6, 1.0 + rr * k)
        fns[bound.kernel_id](bound.fp, bound.ip, bound.state, r, np.eye(6), np.ones(6),
                             chan, 6, out, diag, np.zeros(32))
        qprod *= out[1]
        outs.append((out.copy(), diag.copy(), qprod))
    return outs


def test_rising_innovations_raise_the_process_noise_level():
    policy = FuzzyRQScaling(load_fis(RQ), RQ)
    steady = _drive(policy, 0.0)
    rising = _drive(FuzzyRQScaling(load_fis(RQ), RQ), 0.3)
    # the loop multiplies Q by out[1] every epoch: the product is the logged level
    for out, diag, qprod in rising:
        assert qprod == pytest.approx(diag[2], rel=1e-12) and diag[2] <= Q_MAX
    assert rising[-1][1][2] > 1.5 * steady[-1][1][2]
    assert all(math.isfinite(o[0][2]) for o in rising)
