"""A-KIT recordings whose clock drifts further than the offsets searched at the start.

The reference's 1-Hz stamps of a real A-KIT file drift about 1 s against the IMU's over a
trajectory.  A longer recording, or a clock further off, drifts out of the +-2 s searched
about zero (``akit_timing.MAX_OFFSET_S``); the search then follows the drift in blocks
(``akit_timing.followed_clock``).  Synthetic files with a known clock check that the map
found takes every reference stamp to the time it was written for, on either sign of drift;
that the follow does not depend on the block size; and that what no search lines up is
still refused, naming the file.
"""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders import akit_recording, akit_timing
from fuzzynav.realdata.loaders.akit_recording import load_trajectory, read_table
from fuzzynav.realdata.loaders.akit_timing import ClockMap, ClockSearch, GyroTrack, \
    MAX_OFFSET_S
from fuzzynav.sim.segments import Segment
from fuzzynav.sim.trajectory import generate
from tests.realdata.akit_files import START, write_akit

#: turns of changing rate every 20-30 s: the offset is observable in every block
CYCLE = [Segment("turn", 20, turn_deg=60), Segment("cruise", 20),
         Segment("turn", 20, turn_deg=-90), Segment("climb", 30, pitch_deg=-5),
         Segment("turn", 30, turn_deg=30)]


def _drifting(directory, lag, rate, cycles=8):
    """A 960-s trajectory (by default) whose reference and DVL clock runs ``rate`` times
    the IMU's, stamped ``lag`` late: the stamps of both on one clock, as the real files'."""
    tr = generate(START, CYCLE * cycles, 100.0, 2.0, 0.5)
    idx = write_akit(directory, tr, n=1, lag=lag, rate=rate, lever_y=1.5,
                     dvl_on_imu_clock=False)
    return tr.time_s[idx]


@pytest.fixture(scope="module")
def fast(tmp_path_factory):
    d = tmp_path_factory.mktemp("akit-drift")
    return d, _drifting(d, 0.6, 1.005)


def _search(d):
    """The clock map and search of trajectory 1 in ``d``, as the loader makes them."""
    imu = read_table(d / "IMU_trajectory1.csv", "IMU")
    gt = read_table(d / "corrected" / "GT_trajectory1.csv", "GT")
    dvl = read_table(d / "corrected" / "DVL_trajectory1.csv", "DVL")
    inc = akit_recording.imu_increments(imu[:, 0], imu[:, 1:4], imu[:, 4:7])
    return akit_recording.reference_clock(inc, gt, dvl), gt[:, 0]


@pytest.mark.parametrize("lag,rate", [(0.6, 1.005), (-0.4, 0.995)])
def test_a_drifting_clock_is_followed_to_every_stamp(tmp_path, fast, lag, rate):
    """0.5 % either way over 960 s is 4.8 s of drift: beyond the search at the start.  The
    map takes every reference stamp to the IMU time it was written for within 10 ms (the
    one search's accuracy on the short files is 5 ms at the start), the rate within 2e-5."""
    if rate == 1.005:
        d, stamps = fast
    else:
        d, stamps = tmp_path, _drifting(tmp_path, lag, rate)
    truth = (stamps - lag) / rate
    assert np.max(np.abs(stamps - truth)) > MAX_OFFSET_S + 2.0  # the case is one to follow
    clock = load_trajectory(d, 1).clock
    assert abs(clock.rate - rate) < 2e-5
    np.testing.assert_allclose(clock.to_imu(stamps), truth, rtol=0, atol=0.01)
    assert abs(clock.dvl_offset_s) < 0.02  # the DVL is on the reference's clock


def test_the_search_follows_in_blocks_that_hold_the_map(fast):
    """The blocks' centres move with the drift (one per FOLLOW_BLOCK_S of reference) and
    the map found is inside the offsets searched at every stamp."""
    d, stamps = fast
    (clock, search), labels = _search(d)
    assert search.starts_s.size == int(np.ceil((labels[-1] - labels[0])
                                               / akit_timing.FOLLOW_BLOCK_S))
    assert search.centres_s[0] == 0.0 and search.centres_s[-1] > MAX_OFFSET_S
    assert np.all(np.diff(search.centres_s) >= 0.0)  # a clock running fast: offsets grow
    assert search.inside(clock, labels)
    gap, centre = search.from_centre(clock, labels)
    # half a second or more inside everywhere (block 0, centred on zero, sees 0.6-1.1 s)
    assert np.max(np.abs(gap - centre)) < MAX_OFFSET_S - 0.5
    assert not ClockSearch(labels[:1], np.zeros(1)).inside(clock, labels)


@pytest.mark.parametrize("block", [7, 401 * 3 + 5])
def test_the_followed_clock_is_the_same_whatever_the_block(fast, monkeypatch, block):
    d, _ = fast
    whole = load_trajectory(d, 1)
    for mod in (akit_timing, akit_recording):
        monkeypatch.setattr(mod, "BLOCK_ELEMENTS", block)
    blocked = load_trajectory(d, 1)
    assert blocked.clock == whole.clock
    for a, b in ((whole.imu.dtheta_b, blocked.imu.dtheta_b),
                 (whole.reference.q_bn, blocked.reference.q_bn),
                 (whole.dvl.time_s, blocked.dvl.time_s),
                 (whole.reference_offset_b, blocked.reference_offset_b)):
        assert np.array_equal(a, b)


def test_offsets_further_off_at_the_start_are_still_refused(tmp_path):
    """Stamps 2.6 s late at the start and drifting on: no search about zero lines them up.
    The load stops naming a file, and the message points at the stamps' offset."""
    _drifting(tmp_path, 2.6, 1.004, cycles=5)
    with pytest.raises(InputFileError, match=r"(IMU|GT)_trajectory1\.csv.*"
                       r"(edge of its search.*MAX_OFFSET_S|line up)"):
        load_trajectory(tmp_path, 1)


def test_clock_search_inside_is_the_offset_against_its_block_centre():
    """Closed form: label - t_imu = offset + (1 - 1/rate)(label - offset) for the map
    label = rate t_imu + offset; each stamp is judged against its own block's centre."""
    clock = ClockMap(offset_s=0.5, rate=1.01)
    labels = np.array([0.0, 99.0, 100.0, 250.0])
    search = ClockSearch(np.array([0.0, 100.0, 200.0]), np.array([0.0, 1.5, 2.5]))
    gap, centre = search.from_centre(clock, labels)
    np.testing.assert_allclose(gap, labels - (labels - 0.5) / 1.01, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(centre, [0.0, 0.0, 1.5, 2.5])
    assert search.inside(clock, labels)  # 1.48 s at stamp 99 of the first block: inside
    at_160 = np.array([160.0])  # 2.079 s
    assert search.inside(clock, at_160)  # against 1.5: 0.58 s from the centre
    assert ClockSearch(np.array([0.0, 100.0]), np.array([0.0, 0.2])).inside(clock, at_160)
    # 1.98 s from the centre: inside the +-2 s, but within SEARCH_EDGE_S of its edge
    assert not ClockSearch(np.array([0.0, 100.0]), np.array([0.0, 0.1])).inside(clock, at_160)
    assert not ClockSearch(np.zeros(1), np.zeros(1)).inside(clock, labels)  # 2.97 s at 250


def test_a_track_that_keeps_samples_may_step_back_that_far():
    """A window up to ``keep`` samples before the last one gives the track a fresh one
    gives there (the chain carried on is the same); further back it is refused."""
    rng = np.random.default_rng(3)
    t = np.arange(2001) * 0.01
    dth = rng.normal(0.0, 1e-3, (2000, 3))
    t_ref, q_ref = t[::100], np.tile([1.0, 0.0, 0.0, 0.0], (t[::100].size, 1))
    fresh = GyroTrack(t, dth, t_ref, q_ref, 0.5)
    q_whole, g_whole = fresh.window(0, 1999)
    track = GyroTrack(t, dth, t_ref, q_ref, 0.5, keep=50)
    track.window(1200, 1500)
    q, g = track.window(1150, 1400)
    assert np.array_equal(q, q_whole[1150:1401]) and np.array_equal(g, g_whole[1150:1401])
    with pytest.raises(ValueError, match="forward only"):
        track.window(1099, 1400)
