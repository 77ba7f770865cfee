"""A recording run with no reference epoch left to score is refused before it runs, by
name, instead of running and being reported as a diverged filter (all metrics NaN).

The simulated drive (``tests.realdata.rtklib_files.write_drive``) is written with its last
40 % of solutions float (Q = 2, so not reference epochs: at least 50 % stay fixed, as the
loader requires), and ``--t-start`` is put inside that float part.
"""
import contextlib
import io
from types import SimpleNamespace

import numpy as np
import pytest

from fuzzynav.cli import main
from fuzzynav.errors import FuzzynavError
from fuzzynav.realdata.score import check_scored
from tests.realdata.rtklib_files import write_drive


def _float_tail(path, fraction):
    lines = path.read_text().splitlines()
    data = [i for i, line in enumerate(lines) if line and not line.startswith("%")]
    for i in data[int(len(data) * (1.0 - fraction)):]:
        cols = lines[i].split()
        cols[5] = "2"
        lines[i] = " ".join(cols)
    path.write_text("\n".join(lines) + "\n")


def test_a_t_start_after_the_last_fixed_epoch_is_refused_not_called_diverged(tmp_path):
    truth = write_drive(tmp_path)
    _float_tail(tmp_path / "gnss_1_sf.pos", 0.4)
    t_start = truth.time_s[0] + 0.8 * (truth.time_s[-1] - truth.time_s[0])
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["run", "--data", f"rtklib:{tmp_path}", "--t-start", f"{t_start:.1f}"])
    line = err.getvalue().strip()
    assert code == 2 and out.getvalue() == "", line
    assert len(line.splitlines()) == 1
    assert "no reference epoch to score" in line and "diverged" not in line


def test_check_scored_bounds_are_inclusive():
    ref = SimpleNamespace(time_s=np.array([10.0, 20.0]))
    check_scored(ref, 20.0, 30.0, "r")  # the epoch at the start counts
    check_scored(ref, 0.0, 10.0, "r")   # and at the end
    with pytest.raises(FuzzynavError, match="r: no reference epoch .* 10.0-20.0 s"):
        check_scored(ref, 20.5, 30.0, "r")
