"""Adding a paper: a sixth paper folder outside the package is found, run and compared.

The worked example of docs/architecture.md "Adding a paper": a temporary package
``labpapers.paper005`` holds a ``claims.py``, a ``filters.py`` registering one named filter
and ``scenarios/paper005.toml``; naming it in ``FUZZYNAV_PAPERS`` is all it takes for
``fuzzynav scenarios``, ``run`` and ``compare`` to see it.
"""
from __future__ import annotations

import sys
import textwrap

import pytest

from fuzzynav.cli import main
from fuzzynav.filters.named import FILTERS
from fuzzynav.papers.claims import CLAIMS

CLAIMS_PY = '''
from fuzzynav.papers.claims import PaperClaims, register

register(PaperClaims(prefix="paper005", labels=("paper-005 EKF (claim)",),
                     table={"rms_pos_e_m": ("4.321",)}))
'''

FILTERS_PY = '''
from fuzzynav.filters.adaptation.classical import ConstantScale
from fuzzynav.filters.named import every_sensor, register_filter


@register_filter("ekf-p005", "EKF with every measurement noise inflated x9 (paper 005)")
def _ekf_p005(ctx):
    return every_sensor(ctx, lambda: ConstantScale({}, 9.0))
'''

# a one-minute paper-000 flight at 50 Hz (as tests/tuning/data/tiny.toml)
SCENARIO_TOML = '''
base = "paper000"
description = "paper 005's test flight (a temporary paper folder)"

[imu]
rate_hz = 50.0

[[segments]]
kind = "static"
duration_s = 5.0

[[segments]]
kind = "accelerate"
duration_s = 10.0
speed_change_mps = 15.0

[[segments]]
kind = "turn"
duration_s = 20.0
turn_deg = 90.0
bank = true

[[segments]]
kind = "cruise"
duration_s = 25.0

[sensors.gps]
noise_windows = [{ start_s = 20.0, end_s = 40.0, scale = 5.0 }]
'''


@pytest.fixture
def paper005(tmp_path, monkeypatch):
    """The temporary paper folder, named in FUZZYNAV_PAPERS; its registrations undone after."""
    folder = tmp_path / "labpapers" / "paper005"
    (folder / "scenarios").mkdir(parents=True)
    (tmp_path / "labpapers" / "__init__.py").write_text("")
    (folder / "__init__.py").write_text('"""Paper 005 (a test paper)."""\n')
    (folder / "claims.py").write_text(textwrap.dedent(CLAIMS_PY))
    (folder / "filters.py").write_text(textwrap.dedent(FILTERS_PY))
    (folder / "scenarios" / "paper005.toml").write_text(SCENARIO_TOML)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("FUZZYNAV_PAPERS", "labpapers.paper005")
    yield folder
    FILTERS.pop("ekf-p005", None)
    CLAIMS.pop("paper005", None)
    for name in [m for m in sys.modules if m.split(".")[0] == "labpapers"]:
        del sys.modules[name]


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_a_new_paper_folder_is_listed_run_and_compared(paper005, capsys, sim_cache):
    code, out, err = _run(capsys, "scenarios")
    assert code == 0, err
    assert "paper005 " in out and "paper 005's test flight" in out
    assert "ekf-p005" in out and "inflated x9" in out
    assert "paper000-nominal" in out and "federated-p001" in out  # the built-ins still there

    code, out, _ = _run(capsys, "run", "paper005", "--filter", "ekf-p005", "--cache",
                        str(sim_cache))
    assert code == 0
    assert "east position (m)" in out

    code, out, _ = _run(capsys, "compare", "paper005", "--filters", "ekf,ekf-p005",
                        "--cache", str(sim_cache))
    assert code == 0
    assert "paper-005 EKF (claim)" in out
    east = next(line for line in out.splitlines() if line.startswith("east position"))
    assert east.split()[-1] == "4.321"  # the claim printed beside our two columns


def test_without_the_variable_the_folder_is_not_seen(paper005, capsys, monkeypatch):
    monkeypatch.delenv("FUZZYNAV_PAPERS")
    code, out, _ = _run(capsys, "scenarios")
    assert code == 0
    assert "paper005" not in out


def test_a_paper_folder_that_is_not_a_package_is_one_clear_error(monkeypatch, capsys):
    monkeypatch.setenv("FUZZYNAV_PAPERS", "no_such_lab.paper009")
    code, _, err = _run(capsys, "scenarios")
    assert code == 2
    assert "no_such_lab.paper009" in err and "FUZZYNAV_PAPERS" in err
