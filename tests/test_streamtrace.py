"""The figures' data of a streamed run (``fuzzynav run --output-rate HZ --plot DIR``).

:class:`fuzzynav.streamtrace.StreamTrace` against the whole log's run: at the full output
rate its errors are the whole solution's against the whole truth (1e-12); at a
lower rate they are the kept rows', and each sensor's event log is the first epoch of each
output period of the whole run's event log.  The CLI draws the streamed figures without
simulating the whole log.
"""
import numpy as np
import pytest

from fuzzynav.cli import main
from fuzzynav.experiment import run_on_log
from fuzzynav.metrics import errors_vs_trajectory
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.streamrun import run_streamed

from tests.sim.test_stream import short

_ERR = ("time_s", "pos_m", "vel_mps", "att_rad")


@pytest.mark.parametrize("rate", [None, 2.0])
def test_the_trace_is_the_whole_runs_errors_and_thinned_events(rate):
    scn = short("paper000", 60.0)
    chunk = int(round(7.3 * scn.imu.rate_hz))
    log = simulate(scn, 1)
    whole = run_on_log(log, "fuzzy", chunk_samples=chunk, output_rate_hz=rate).result
    got = run_streamed(scn, 1, "fuzzy", chunk_samples=chunk, output_rate_hz=rate,
                       trace=True).trace
    want = errors_vs_trajectory(whole, log.truth)
    # the times are copied; the errors are the same arithmetic on row slices of the truth
    # (vectorised ufuncs may round a slice's tail differently on another CPU): 1e-12
    np.testing.assert_array_equal(got.errors.time_s, want.time_s)
    for f in _ERR[1:]:
        np.testing.assert_allclose(getattr(got.errors, f), getattr(want, f), rtol=1e-12,
                                   atol=1e-15, err_msg=f)
    assert got.errors.time_s.size == whole.time_s.size > 10
    assert got.events.keys() == whole.events.keys() == {"gps", "pol"}
    for nm, ev in whole.events.items():
        if rate is None:
            sel = np.arange(ev.time_s.size)
        else:  # the first epoch of each 0.5-s period, by a loop over the whole log
            sel, last = [], None
            for i, t in enumerate(ev.time_s):
                if last is None or np.floor(t * rate) > last:
                    sel.append(i)
                    last = np.floor(t * rate)
            sel = np.array(sel)
            assert 0 < sel.size < ev.time_s.size or nm == "gps"
        for f in ("time_s", "nis", "diag", "flag"):
            np.testing.assert_array_equal(getattr(got.events[nm], f), getattr(ev, f)[sel],
                                          err_msg=f"{nm}.{f}")
        assert got.events[nm].diag_names == ev.diag_names


def test_the_cli_plots_a_streamed_run_without_the_whole_log(tmp_path, monkeypatch, capsys):
    import fuzzynav.sim.sensor_log as sensor_log

    scn_file = tmp_path / "s.toml"
    scn_file.write_text('base = "paper000"\nname = "p0-stream"\n')

    def refused(*a, **k):
        raise AssertionError("the whole log was simulated")

    monkeypatch.setattr(sensor_log, "simulate", refused)
    code = main(["run", str(scn_file), "--filter", "fuzzy", "--output-rate", "1",
                 "--plot", str(tmp_path / "fig"), "--cache", str(tmp_path / "c")])
    out = capsys.readouterr().out
    assert code == 0, out
    for fig in ("p0-stream_errors.png", "p0-stream_adaptation.png"):
        path = tmp_path / "fig" / fig
        assert path.stat().st_size > 10_000 and f"wrote {path}" in out
