"""The start's second heading: an IMU whose forward axis points backward (the walk of
``test_slow_platform`` read with a mounting that reverses body x and y: a phone carried
back to front) is refused by ``heading=track`` and ``min_speed=0.5`` (180 deg from the
specific-force heading), never run at 180 deg off with exit 0; the unreversed walk passes
(``test_slow_platform``); an explicit ``heading=DEG`` is not second-guessed."""
import math

import pytest

from fuzzynav.realdata.start_check import check_headings
from fuzzynav.errors import InputFileError
from tests.realdata.test_slow_platform import PROTOCOL, _run, write_walk


@pytest.fixture(scope="module")
def reversed_walk(tmp_path_factory):
    return write_walk(tmp_path_factory.mktemp("reversed_walk"), forward=-1.0)


@pytest.mark.parametrize("query", ["heading=track&baseline=15", "min_speed=0.5"])
def test_a_reversed_imu_is_refused_with_both_headings(reversed_walk, query):
    code, out, err = _run("run", "--data", f"rtklib:{reversed_walk}?{query}", *PROTOCOL)
    assert code == 2 and out == "", err
    line = err.strip()
    assert len(line.splitlines()) == 1
    assert "specific-force" in line and "heading=DEG" in line and "180" in line


def test_check_headings_threshold():
    check_headings(("track", 0.0, math.radians(2)), ("specific-force", math.radians(15), 0.0))
    with pytest.raises(InputFileError, match="disagree"):
        check_headings(("track", 0.0, math.radians(2)), ("specific-force", math.pi, 0.0))
