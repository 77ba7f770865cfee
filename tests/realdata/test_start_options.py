"""The start options of a data spec (``rtklib:DIR?key=value&...``) and what they change."""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.sources import data_options, split_options
from fuzzynav.realdata.start_options import StartOptions, parse_start_options


def test_no_options_are_the_car_defaults():
    assert parse_start_options("") == StartOptions()
    o = StartOptions()
    # docs/data.md §5: rest below 0.2 m/s, course above 2 m/s in 30 s (60 s specific force)
    assert (o.rest_speed_mps, o.min_speed_mps) == (0.2, 2.0)
    assert o.window_for("course") == 30.0 and o.window_for("specific-force") == 60.0
    assert o.method(True) == "course" and o.method(False) == "specific-force"


def test_values_are_read_with_their_units():
    o = parse_start_options("min_speed=0.5&window=45&heading=track&baseline=12&"
                            "heading_sigma=20&lever_arm=0.1,-0.2,0.3&min_rest=0")
    assert o.min_speed_mps == 0.5 and o.window_for("specific-force") == 45.0
    assert o.method(False) == "track" and o.track_baseline_m == 12.0
    assert o.heading_sigma_deg == 20.0 and o.min_rest_s == 0.0
    np.testing.assert_allclose(o.lever_arm_b_m, (0.1, -0.2, 0.3))
    given = parse_start_options("heading=-45.5")
    assert given.heading == "given" and given.heading_deg == -45.5


def test_an_error_names_the_data_spec_and_the_option():
    with pytest.raises(InputFileError, match=r"--data rtklib:d option window: '0'"):
        parse_start_options("window=0", "rtklib:d")


@pytest.mark.parametrize("text", ["0,1e6,0", "-1000.5,0,0", "0,0,1e300"])
def test_a_lever_arm_longer_than_any_vehicle_is_refused(text):
    """Scenarios cap the lever arm at 1 km; the start option took 1e6 m."""
    with pytest.raises(InputFileError, match=r"option lever_arm: .*within \+-1000 m"):
        parse_start_options(f"lever_arm={text}", "rtklib:d")
    assert parse_start_options("lever_arm=1000,-1000,0").lever_arm_b_m == (1e3, -1e3, 0.0)


def test_the_query_is_split_off_the_spec(tmp_path):
    assert split_options("rtklib:d:2?min_speed=1") == ("rtklib:d:2", "min_speed=1")
    assert split_options("rtklib:d") == ("rtklib:d", None)
    odd = tmp_path / "a?b"
    odd.mkdir()
    assert split_options(f"rtklib:{odd}") == (f"rtklib:{odd}", None)  # a directory's own '?'
    assert data_options("rtklib:d") is None
    assert data_options("rtklib:d?min_speed=1").min_speed_mps == 1.0


def test_lever_arm_option_replaces_the_mountings(tmp_path):
    from fuzzynav.realdata.loaders.rtklib import load_rtklib
    from tests.realdata.rtklib_files import write_drive

    write_drive(tmp_path)
    rec = load_rtklib(tmp_path, start=StartOptions(lever_arm_b_m=(0.0, 0.5, 1.0)))
    np.testing.assert_allclose(rec.gnss.meta["lever_arm_b"], (0.0, 0.5, 1.0))
    np.testing.assert_allclose(load_rtklib(tmp_path).gnss.meta["lever_arm_b"], 0.0)


def test_track_heading_needs_no_receiver_velocity():
    """A receiver without velocities (NaN, as a .pos without the velocity block reads): the
    track still gives the heading of a platform walking north-east at 1.4 m/s."""
    from types import SimpleNamespace

    from fuzzynav.realdata.coarse_align import heading_from_track

    t = np.arange(0.0, 40.0, 0.01)
    imu = SimpleNamespace(time_s=t, dtheta_b=np.zeros((t.size - 1, 3)),
                          dv_b=np.zeros((t.size - 1, 3)))
    tg = np.arange(0.0, 40.0, 0.25)
    lat0, r = 0.7, 6.378e6
    d = 1.4 * np.maximum(tg - 5.0, 0.0) / np.sqrt(2.0)   # metres east and north
    z = np.column_stack([lat0 + d / r, d / (r * np.cos(lat0)), np.zeros(tg.size),
                         np.full((tg.size, 3), np.nan)])
    gnss = SimpleNamespace(time_s=tg, z=z)
    heading = heading_from_track(imu, gnss, 5.0, np.eye(3), np.zeros(3), 30.0, 10.0)
    assert abs(np.degrees(heading) - 45.0) < 0.5  # radius of the earth model vs 6378 km
