"""Per-segment metrics (fuzzynav.metrics_segments) against rms_metrics of each segment's
epochs, chunked against whole, and the boundary, start and NaN rules."""
import numpy as np
import pytest

from fuzzynav import block_sums
from fuzzynav.metrics import NavErrors, StreamingRms, rms_metrics
from fuzzynav.metrics_segments import (SEGMENT_METRICS, SegmentRms, key, scenario_edges_s,
                                       segment_metrics)
from fuzzynav.sim.scenario import load_scenario
from tests.floats import sum_order_rtol

EDGES = np.array([0.0, 5.0, 15.0, 35.0, 60.0])
#: SegmentRms's name -> rms_metrics' name of the same quantity over a segment's epochs
SAME_AS = {"rms_pos_h_m": "rms_pos_h_m", "max_pos_h_m": "max_pos_h_m",
           "end_pos_h_m": "final_pos_h_m", "rms_pos_u_m": "rms_pos_u_m",
           "rms_vel_h_mps": "rms_vel_h_mps", "rms_heading_deg": "rms_heading_deg"}


def _errors(seed=0, rate_hz=10.0, end=60.0):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, end + 1e-9, 1.0 / rate_hz)   # an epoch on every edge, and at the end
    n = t.size
    return NavErrors(t, rng.normal(0, 2, (n, 3)), rng.normal(0, 0.1, (n, 3)),
                     rng.normal(0, 1e-3, (n, 3)))


def _cut(err, a, b):
    return NavErrors(err.time_s[a:b], err.pos_m[a:b], err.vel_mps[a:b], err.att_rad[a:b])


def _segment_of_each_epoch(t, edges):
    """The rule written out: [edges[j], edges[j+1]); the end belongs to the last one."""
    return np.array([min(int(np.flatnonzero(edges <= x)[-1]), edges.size - 2) for x in t])


@pytest.mark.parametrize("t_start", [0.0, 12.0])
def test_each_segment_is_rms_metrics_of_its_epochs(t_start):
    err = _errors()
    got = segment_metrics(err, EDGES, t_start)
    seg = _segment_of_each_epoch(err.time_s, EDGES)
    for j in range(EDGES.size - 1):
        rows = np.flatnonzero((seg == j) & (err.time_s >= t_start))
        if not rows.size:   # before the scoring start: nothing scored
            assert all(np.isnan(got[key(j, m)]) for m in SEGMENT_METRICS), j
            continue
        ref = rms_metrics(_cut(err, rows[0], rows[-1] + 1))
        assert rows[-1] - rows[0] + 1 == rows.size    # a segment's epochs are contiguous
        for m, r in SAME_AS.items():
            assert got[key(j, m)] == pytest.approx(ref[r], rel=sum_order_rtol(rows.size)), (j, m)
    assert np.isnan(got[key(0, "rms_pos_h_m")]) == (t_start > EDGES[1])


def test_an_epoch_on_a_boundary_opens_the_next_segment():
    t = np.array([0.0, 5.0, 15.0, 60.0])
    err = NavErrors(t, np.array([[1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0], [4.0, 0, 0]]),
                    np.zeros((4, 3)), np.zeros((4, 3)))
    got = segment_metrics(err, EDGES)
    # 0 s -> segment 1, 5 s -> 2, 15 s -> 3, none in 4 but the run's end (60 s) -> 4
    assert [got[key(j, "max_pos_h_m")] for j in range(4)] == [1.0, 2.0, 3.0, 4.0]


@pytest.mark.parametrize("block", [None, 9])
def test_chunked_equals_whole_and_the_streaming_rms_carries_it(block, monkeypatch):
    if block:   # segments of many blocks, chunks cut across them (fuzzynav.block_sums)
        monkeypatch.setattr(block_sums, "BLOCK_COLUMNS", block)
    err = _errors(seed=3)
    whole = {**rms_metrics(err, 2.0), **segment_metrics(err, EDGES, 2.0)}
    rng = np.random.default_rng(7)
    for _ in range(20):
        cuts = np.unique(np.concatenate([[0], rng.integers(1, err.time_s.size, 5),
                                         [err.time_s.size]]))
        acc = StreamingRms(2.0, None, SegmentRms(EDGES, 2.0))
        for a, b in zip(cuts[:-1], cuts[1:]):
            acc.add(_cut(err, a, b))
        # the same errors given, the same additions whatever the chunks: to the bit
        assert acc.metrics() == whole


def test_squares_add_up_to_the_whole_runs():
    """Conservation: the segments' n_j rms_j^2 sum to the run's N rms^2."""
    err = _errors(seed=5)
    got = segment_metrics(err, EDGES)
    n = np.bincount(_segment_of_each_epoch(err.time_s, EDGES))
    total = sum(n[j] * got[key(j, "rms_pos_h_m")] ** 2 for j in range(n.size))
    whole = rms_metrics(err)["rms_pos_h_m"]
    assert total / err.time_s.size == pytest.approx(whole ** 2, rel=1e-12)


def test_a_nan_stays_in_its_segment():
    err = _errors()
    err.pos_m[200] = np.nan   # t = 20 s: segment 3
    got = segment_metrics(err, EDGES)
    assert np.isnan(got[key(2, "max_pos_h_m")]) and np.isnan(got[key(2, "rms_pos_h_m")])
    assert all(np.isfinite(got[key(j, "max_pos_h_m")]) for j in (0, 1, 3))


def test_edges_of_a_scenario_and_bad_edges():
    scn = load_scenario("paper000")
    edges = scenario_edges_s(scn)
    assert edges[0] == 0.0 and edges[-1] == scn.duration_s
    assert edges.size == len(scn.segments) + 1
    for bad in ([0.0], [0.0, 5.0, 5.0], [[0.0, 1.0]]):
        with pytest.raises(ValueError, match="segment edges"):
            SegmentRms(bad)
