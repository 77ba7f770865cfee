"""``fuzzynav run/compare SCENARIO --segments``: the per-segment table and JSON, whole and
streamed, and where it is refused."""
import json
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.cli import main
from fuzzynav.experiment import monte_carlo, run_on_log
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from fuzzynav.metrics_segments import SEGMENT_METRICS, key, scenario_edges_s
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import simulate
from tests.floats import METRICS_RTOL, sum_order_rtol

TINY = Path(__file__).resolve().parents[1] / "tuning" / "data" / "tiny.toml"


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _json(capsys, *argv):
    code, out, err = _run(capsys, *argv, "--json")
    assert code == 0, err
    return json.loads(out)


def test_json_segments_are_the_runs_errors_inside_each_segment(capsys, sim_cache):
    scn = load_scenario(TINY)
    doc = _json(capsys, "run", TINY, "--filter", "fakf", "--segments", "--mc", "2",
                "--t-start", "8", "--cache", sim_cache)
    segs = doc["segments"]
    edges = scenario_edges_s(scn)
    assert [s["kind"] for s in segs] == [s.kind for s in scn.segments]
    assert [s["start_s"] for s in segs] == list(edges[:-1])
    assert [s["end_s"] for s in segs] == list(edges[1:])
    for i, seed in enumerate((0, 1)):   # against the errors of the same run, cut by hand
        log = simulate(scn, seed, sim_cache)
        res = run_on_log(log, "fakf", t_start_s=8.0).result
        err = errors_vs_trajectory(res, log.truth)
        for j, seg in enumerate(segs):
            inside = (err.time_s >= max(edges[j], 8.0)) & (err.time_s < edges[j + 1])
            if j == len(segs) - 1:
                inside |= err.time_s >= edges[-1]
            got = seg["filters"]["fakf"]
            assert set(got) == set(SEGMENT_METRICS)
            if not inside.any():   # the first segment (0-5 s) ends before --t-start
                assert got["rms_pos_h_m"]["values"][i] is None
                continue
            rows = np.flatnonzero(inside)
            h = np.hypot(err.pos_m[rows, 0], err.pos_m[rows, 1])
            rel = sum_order_rtol(rows.size)
            assert got["rms_pos_h_m"]["values"][i] == pytest.approx(
                np.sqrt(np.mean(h ** 2)), rel=rel)
            assert got["max_pos_h_m"]["values"][i] == np.max(h)
            assert got["end_pos_h_m"]["values"][i] == h[-1]
    # the run's own table is unchanged by --segments
    plain = _json(capsys, "run", TINY, "--filter", "fakf", "--mc", "2", "--t-start", "8",
                  "--cache", sim_cache)
    assert plain["filters"] == doc["filters"] and "segments" not in plain


def test_streamed_segments_equal_the_whole_runs(capsys, sim_cache):
    args = ("compare", TINY, "--filters", "ekf,fakf", "--segments", "--cache", sim_cache)
    whole = _json(capsys, *args)
    streamed = _json(capsys, *args, "--chunk", "7", "--output-rate", "10")
    # simulated and scored chunk by chunk, each segment's sums in blocks from its first
    # epoch (fuzzynav.block_sums), of errors formed on the chunks' slices (two paths)
    for a, b in zip(streamed["segments"], whole["segments"]):
        assert a["kind"] == b["kind"]
        for f in ("ekf", "fakf"):
            for m in SEGMENT_METRICS:
                np.testing.assert_allclose(a["filters"][f][m]["values"],
                                           b["filters"][f][m]["values"], rtol=METRICS_RTOL,
                                           err_msg=m)


def test_the_table_has_a_row_per_segment(capsys, sim_cache):
    code, out, err = _run(capsys, "compare", TINY, "--filters", "ekf,fakf", "--segments",
                          "--cache", sim_cache)
    assert code == 0, err
    table = out[out.index("per motion segment"):].splitlines()
    rows = [line for line in table if line[:1].isdigit()]
    assert [r.split()[1] for r in rows] == [s.kind for s in load_scenario(TINY).segments]
    assert "fakf vs ekf h RMS" in table[1] and "ekf heading RMS (deg)" in table[1]


def test_segments_do_not_change_the_metrics_and_sum_to_the_run(sim_cache):
    """Conservation on a real run: the segments' squared sums add to the run's RMS."""
    scn = load_scenario(TINY)
    df = monte_carlo(scn, ["ekf"], [3], cache_dir=sim_cache, segments=True)
    plain = monte_carlo(scn, ["ekf"], [3], cache_dir=sim_cache)
    for c in plain.columns:
        assert df[c].iloc[0] == plain[c].iloc[0] or (
            isinstance(plain[c].iloc[0], float) and np.isnan(plain[c].iloc[0])), c
    log = simulate(scn, 3, sim_cache)
    err = errors_vs_trajectory(run_on_log(log, "ekf").result, log.truth)
    edges = scenario_edges_s(scn)
    n = np.histogram(err.time_s, np.append(edges[:-1], np.inf))[0]
    total = sum(n[j] * df[key(j, "rms_pos_h_m")].iloc[0] ** 2 for j in range(n.size))
    assert total / n.sum() == pytest.approx(rms_metrics(err)["rms_pos_h_m"] ** 2, rel=1e-12)


def test_plot_marks_the_segments(capsys, monkeypatch, tmp_path, sim_cache):
    import fuzzynav.plots

    drawn = []
    real = fuzzynav.plots.error_curves

    def error_curves(errors, title="", segments=()):
        fig = real(errors, title, segments)
        drawn.append((list(segments), fig))
        return fig

    monkeypatch.setattr(fuzzynav.plots, "error_curves", error_curves)
    code, _, err = _run(capsys, "run", TINY, "--filter", "ekf", "--segments", "--plot",
                        tmp_path, "--cache", sim_cache)
    assert code == 0, err
    assert (tmp_path / "tiny_errors.png").stat().st_size > 0
    (spans, fig), = drawn
    scn = load_scenario(TINY)
    edges = scenario_edges_s(scn)
    assert spans == [(edges[j], edges[j + 1], f"{j + 1} {s.kind}")
                     for j, s in enumerate(scn.segments)]
    first = fig.axes[0]
    assert len(first.patches) == len(spans) // 2           # every other segment shaded
    assert [t.get_text() for t in first.texts] == [label for _, _, label in spans]
    code, _, err = _run(capsys, "run", TINY, "--filter", "ekf", "--plot", tmp_path,
                        "--cache", sim_cache)
    assert code == 0 and drawn[-1][0] == [] and not drawn[-1][1].axes[0].patches


@pytest.mark.parametrize("argv, fragment", [
    (["run", "--data", "rtklib:nowhere", "--segments"], "--segments: only with a simulated"),
    (["run", "paper000", "--align", "align-kf", "--segments"], "--segments: not with --align"),
    (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--segments"],
     "--segments: not for alignment scenarios"),
])
def test_refused_where_there_are_no_segments(capsys, argv, fragment):
    code, _, err = _run(capsys, *argv)
    assert code == 2 and fragment in err and err.count("\n") == 1, err


def test_monte_carlo_refuses_segments_with_seed_runs():
    from fuzzynav.errors import FuzzynavError

    with pytest.raises(FuzzynavError, match="segments"):
        monte_carlo(load_scenario(TINY), ["x"], [0], seed_runs=lambda s: None, segments=True)
