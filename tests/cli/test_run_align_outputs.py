"""``fuzzynav run SCENARIO --align A``: its JSON, its figures and its diverged runs, whole
and streamed (``--chunk``), each checked against the aligned run made through the API."""
import json
from dataclasses import replace

import numpy as np
import pytest

import fuzzynav.plots
import fuzzynav.runpath
import fuzzynav.streamrun
from fuzzynav.align.chain import run_aligned
from fuzzynav.cli import main
from fuzzynav.metrics import errors_vs_trajectory
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import simulate

SCN = "paper000-nominal"          # a 60-s opening rest, then the flight
STREAMED = ("--chunk", "45", "--output-rate", "1")
#: a streamed run against the whole one: the same arithmetic per epoch except for the
#: order of sums (tests/align/test_streamed_alignment.py holds the metrics to this)
RTOL, ATOL = 1e-9, 1e-12


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_json_holds_each_seeds_aligned_and_navigation_metrics(capsys, sim_cache):
    code, out, err = _run(capsys, "run", SCN, "--filter", "ekf", "--align", "align-kf",
                          "--mc", "2", "--seed", "3", "--json", "--cache", sim_cache)
    assert code == 0, err
    doc = json.loads(out)
    assert doc["scenario"] == SCN and doc["seeds"] == [3, 4]
    (label, rows), = doc["filters"].items()
    assert label == "align-kf -> ekf"
    assert {"align_heading_err_deg", "align_level_err_deg", "rms_pos_e_m",
            "rms_heading_deg"} <= set(rows)
    scn = load_scenario(SCN)
    for i, seed in enumerate((3, 4)):   # the same run made through the API, same seed
        metrics = run_aligned(simulate(scn, seed, sim_cache), "ekf").metrics
        for key, summary in rows.items():
            assert summary["values"][i] == metrics[key], (seed, key)
    assert rows["rms_pos_e_m"]["mean"] == pytest.approx(np.mean(rows["rms_pos_e_m"]["values"]))


@pytest.mark.parametrize("streamed", [False, True])
def test_plot_draws_the_navigation_from_the_alignments_end(capsys, monkeypatch, tmp_path,
                                                          sim_cache, streamed):
    drawn = {}
    real = fuzzynav.plots.error_curves

    def error_curves(errors, title="", segments=()):
        drawn.update(errors)
        return real(errors, title, segments)

    monkeypatch.setattr(fuzzynav.plots, "error_curves", error_curves)
    code, out, err = _run(capsys, "run", SCN, "--filter", "fakf", "--align", "align-kf",
                          "--plot", tmp_path, "--cache", sim_cache,
                          *(STREAMED if streamed else ()))
    assert code == 0, err
    assert (tmp_path / f"{SCN}_errors.png").stat().st_size > 0
    assert (tmp_path / f"{SCN}_adaptation.png").stat().st_size > 0   # fakf adapts
    assert "aligned with align-kf" in out
    errors = drawn["align-kf -> fakf"]
    log = simulate(load_scenario(SCN), 0, sim_cache)
    whole = run_aligned(log, "fakf")
    ref = errors_vs_trajectory(whole.result, log.truth)
    assert ref.time_s[0] == whole.metrics["align_end_s"] == 60.0
    if streamed:   # the kept 1-Hz outputs: the whole run's at those epochs (another path)
        assert errors.time_s[0] == pytest.approx(60.0, abs=ATOL)
        assert np.all(np.diff(errors.time_s) == pytest.approx(1.0))
        at = np.searchsorted(ref.time_s, errors.time_s - 1e-6)   # the nearest whole epoch
        np.testing.assert_allclose(ref.time_s[at], errors.time_s, rtol=0, atol=1e-9)
        for field in ("pos_m", "vel_mps", "att_rad"):
            np.testing.assert_allclose(getattr(errors, field), getattr(ref, field)[at],
                                       rtol=RTOL, atol=ATOL, err_msg=field)
    else:          # the very run of the table: the same arrays
        for field in ("time_s", "pos_m", "vel_mps", "att_rad"):
            np.testing.assert_array_equal(getattr(errors, field), getattr(ref, field))


def _nan_half(res):
    lla = res.lla.copy()
    lla[lla.shape[0] // 2:] = np.nan
    return replace(res, lla=lla)


@pytest.mark.parametrize("streamed", [False, True])
def test_a_diverged_aligned_run_prints_no_table_and_exits_3(capsys, monkeypatch, sim_cache,
                                                            tmp_path, streamed):
    if streamed:   # a streamed run's metrics come from its running sums
        real = fuzzynav.streamrun.StreamingRms.metrics
        monkeypatch.setattr(fuzzynav.streamrun.StreamingRms, "metrics",
                            lambda self: {**real(self), "rms_pos_e_m": float("nan")})
    else:
        real = fuzzynav.runpath.run_filter
        monkeypatch.setattr(fuzzynav.runpath, "run_filter",
                            lambda *a, **k: _nan_half(real(*a, **k)))
    for flags in ((), ("--json",), ("--plot", tmp_path / "fig")):
        code, out, err = _run(capsys, "run", SCN, "--filter", "ekf", "--align", "align-kf",
                              "--seed", "2", "--cache", sim_cache, *flags,
                              *(STREAMED if streamed else ()))
        assert code == 3 and out == "" and err.count("\n") == 1, (flags, err)
        assert f"filter ekf diverged on scenario {SCN} seed 2" in err and "= nan" in err
        assert not (tmp_path / "fig").exists()
