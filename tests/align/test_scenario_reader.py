"""Alignment scenarios are read by the navigation scenarios' reader: ``base =`` a built-in or
a file beside, tables merged key by key, one clear error naming the file and key."""
import pytest

from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.errors import InputFileError


def _write(path, text):
    path.write_text('kind = "alignment"\n' + text)
    return path


def test_a_file_derives_from_a_built_in_and_from_a_file_beside_it(tmp_path):
    base = load_alignment_scenario("paper002")
    _write(tmp_path / "mid.toml", 'base = "paper002"\nduration_s = 120.0\n[imu]\nrate_hz = 10.0\n')
    top = _write(tmp_path / "top.toml", 'base = "mid.toml"\nthreshold_arcmin = 30.0\n')
    scn = load_alignment_scenario(top)
    assert (scn.duration_s, scn.threshold_arcmin, scn.imu.rate_hz) == (120.0, 30.0, 10.0)
    # untouched keys, tables merged key by key: the rest of [imu] is paper002's
    assert scn.lat_deg == base.lat_deg and scn.imu.gyro_bias_dph == base.imu.gyro_bias_dph
    # a file without a name is its stem, not the built-in's (that would borrow its claims)
    assert scn.name == "top"


@pytest.mark.parametrize("text, fragment", [
    ('base = "paper000"\n', "unknown alignment scenario 'paper000'"),
    ('base = "../up.toml"\n', "points outside the scenario's own directory"),
    ("base = 3\n", "must be a scenario name or a file path"),
])
def test_a_bad_base_is_one_error_naming_the_file_and_key(tmp_path, text, fragment):
    path = _write(tmp_path / "bad.toml", text)
    with pytest.raises(InputFileError) as exc:
        load_alignment_scenario(path)
    assert str(path) in str(exc.value) and "base" in str(exc.value)
    assert fragment in str(exc.value)


def test_a_base_loop_is_refused(tmp_path):
    _write(tmp_path / "a.toml", 'base = "b.toml"\n')
    _write(tmp_path / "b.toml", 'base = "a.toml"\n')
    with pytest.raises(InputFileError, match="loop"):
        load_alignment_scenario(tmp_path / "a.toml")
