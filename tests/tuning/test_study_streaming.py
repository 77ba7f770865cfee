"""A study's ``[streaming]`` table (:mod:`fuzzynav.tuning.study_streaming`).

Held runs (their log simulated once, filtered in one piece or cut into chunks) and long
runs (simulated again chunk by chunk for every run) are the same data and the same filter
arithmetic with the same streamed sums (:mod:`fuzzynav.block_sums`): their metrics agree
with each other and with a whole-run study's to the bit.
"""
from __future__ import annotations

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.fuzzy import load_fis
from fuzzynav.sim import budget
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import SensorLog, simulate
from fuzzynav.tuning import study_streaming
from fuzzynav.tuning.evaluate import run_table
from fuzzynav.tuning.objective import Evaluator
from fuzzynav.tuning.study_config import load_study_config
from tests.floats import same_metrics
from tests.tuning.studies import GPS, TINY, finished_study, write_study

CHUNKS = {"chunk_s": 7.0, "output_rate_hz": 1.0}
#: a run twice a held log's size is streamed: the tiny flight with hold_log_mb = 0
LONG = {**CHUNKS, "hold_log_mb": 0.0}


def _evaluator(tmp_path, name, **changes):
    return Evaluator(load_study_config(write_study(tmp_path, file_name=f"{name}.toml",
                                                   **changes)))


def _metrics(ev, runs):
    systems = {"gps": load_fis(GPS)}
    return [(ev.baseline(*run), ev.run_systems(systems, *run).metrics) for run in runs]


def test_held_and_long_runs_give_the_same_metrics_to_the_bit(tmp_path, monkeypatch):
    # the held runs cut at the long runs' chunks (not in one piece): the same slices, the
    # same arithmetic, so equal to the bit
    monkeypatch.setattr(study_streaming.StudyStreaming, "one_piece", lambda *a: False)
    held = _evaluator(tmp_path, "held", streaming=CHUNKS)
    long = _evaluator(tmp_path, "long", streaming=LONG)
    runs = held.config.train
    got_held = _metrics(held, runs)
    # the compared filters of the test table go the same way
    table = [run_table(held, {}, held.config.test, held.config.compare)]
    assert all(isinstance(held.log(*r), SensorLog) for r in runs)
    # a long run is never simulated whole: only chunk by chunk, for each of its runs
    monkeypatch.setattr(study_streaming, "simulate", _refuse_whole)
    got_long = _metrics(long, runs)
    table.append(run_table(long, {}, long.config.test, long.config.compare))
    assert not any(isinstance(long.log(*r), SensorLog) for r in runs)
    assert got_long == got_held
    cols = [c for c in table[0] if c.startswith(("rms_", "max_")) or c.endswith("ratio")]
    assert table[0][cols].equals(table[1][cols])


def _refuse_whole(*args, **kwargs):
    raise AssertionError("a long run of a [streaming] study was simulated whole")


@pytest.mark.parametrize("cut", [False, True])
def test_a_streamed_study_scores_the_whole_runs_metrics(tmp_path, monkeypatch, cut):
    """Held in one piece (the tiny run's 601 outputs fit hold_log_mb: the whole-run study's
    metrics to the bit) or cut into 7-s chunks (outputs made to weigh 1 MB a row: within
    tests/floats.py's METRICS_RTOL)."""
    chunks = []
    real = study_streaming.run

    def spy(source, spec, options=None, setup=None, **kw):
        chunks.append(kw["chunk_samples"])
        return real(source, spec, options, setup, **kw)

    monkeypatch.setattr(study_streaming, "run", spy)
    if cut:
        monkeypatch.setattr(budget, "BYTES_PER_OUTPUT_ROW", 2**20)
    whole = _evaluator(tmp_path, "whole")
    held = _evaluator(tmp_path, "held", streaming=CHUNKS)
    runs = whole.config.train
    got_whole, got_held = _metrics(whole, runs), _metrics(held, runs)
    assert chunks and set(chunks) == ({350} if cut else {None})  # 7 s at 50 Hz, or none
    if cut:   # the same sums of errors formed on the chunks' slices: two paths
        for held_run, whole_run in zip(got_held, got_whole):
            for h, w in zip(held_run, whole_run):
                same_metrics(h, w)
    else:     # the same arrays scored by the same accumulator
        assert got_held == got_whole
    base_h, cand_h = got_held[0]
    assert cand_h["rms_pos_m"] != base_h["rms_pos_m"]  # the candidate did adapt


def test_one_piece_is_the_outputs_against_hold_log_mb():
    st = study_streaming.StudyStreaming(hold_log_bytes=600 * budget.BYTES_PER_OUTPUT_ROW)
    assert st.one_piece(60.0, 10.0) and not st.one_piece(60.1, 10.0)
    assert not study_streaming.StudyStreaming(hold_log_bytes=0.0).one_piece(1.0, 10.0)
    # what a held run may keep in one piece joins its working estimate, bounded by the budget
    scn = load_scenario(str(TINY))
    args = (scn.duration_s, scn.imu.rate_hz, scn.sensors)
    streamed = budget.streamed_estimate(*args)
    assert study_streaming.StudyStreaming().working_bytes(*args) == streamed + \
        budget.output_bytes(scn.duration_s * 10.0)
    assert study_streaming.StudyStreaming(hold_log_bytes=0.0).working_bytes(*args) == streamed


def test_a_study_runs_its_trials_on_long_runs(tmp_path, monkeypatch):
    """A whole (tiny) random-sampler study: the streamed-long trials' values are the held
    ones, trial by trial (the held runs cut at the same chunks)."""
    monkeypatch.setattr(study_streaming.StudyStreaming, "one_piece", lambda *a: False)
    values = []
    for name, streaming in (("held", CHUNKS), ("long", LONG)):
        (tmp_path / name).mkdir()
        _, study = finished_study(tmp_path / name, None, trials=3, streaming=streaming)
        values.append([t.value for t in study.trials])
    assert len(values[0]) == 3 and all(np.isfinite(values[0]))
    assert values[1] == values[0]


RUN = """
name = "long"
[start]
lat_deg = 30.0
lon_deg = 110.0
speed_mps = 10.0
[imu]
rate_hz = 100.0
[[segments]]
kind = "cruise"
duration_s = 20000.0
[sensors.gps]
kind = "gnss"
"""


def test_a_run_too_long_to_hold_asks_for_the_table(tmp_path, monkeypatch):
    """2e6 samples: ~2.7 GB simulated whole against a 0.5-GB limit, ~104 MB in chunks
    (tests/sim/test_budget.py works the figures by hand)."""
    monkeypatch.setenv(budget.ENV_VAR, "0.5")
    scn = tmp_path / "long.toml"
    scn.write_text(RUN)
    runs = {"scenarios": [str(scn)], "seeds": [0]}
    path = write_study(tmp_path, file_name="refused.toml", train=runs,
                       test={"scenarios": [str(TINY)], "seeds": [5]})
    with pytest.raises(InputFileError) as exc:
        load_study_config(path)
    assert exc.value.where == "streaming" and str(path) in str(exc.value)
    assert "needs ~2.67 GB simulated whole" in exc.value.what
    assert "give the study file a [streaming] table" in exc.value.what
    path = write_study(tmp_path, file_name="streamed.toml", train=runs, streaming=CHUNKS,
                       test={"scenarios": [str(TINY)], "seeds": [5]})
    cfg = load_study_config(path)
    assert not cfg.streaming.holds(load_scenario(str(scn)))  # its log is ~580 MB
    assert cfg.streaming.holds(load_scenario(str(TINY)))
    assert cfg.streaming.chunk_samples(load_scenario(str(scn)).imu.rate_hz) == 700


@pytest.mark.parametrize("table, where, what", [
    ({"chunk_s": 0.0}, "streaming.chunk_s", "must lie in (0.0, inf]"),
    ({"output_rate_hz": -1.0}, "streaming.output_rate_hz", "must lie in (0.0, inf]"),
    ({"hold_log_mb": -1.0}, "streaming.hold_log_mb", "must lie in [0.0, inf]"),
    ({"chunk": 5.0}, "streaming.chunk", "unknown key"),
])
def test_bad_streaming_keys_name_the_key(tmp_path, table, where, what):
    with pytest.raises(InputFileError) as exc:
        load_study_config(write_study(tmp_path, streaming=table))
    assert exc.value.where == where and what in exc.value.what


def test_defaults_are_the_command_lines(tmp_path):
    cfg = load_study_config(write_study(tmp_path, streaming={}))
    assert cfg.streaming.output_rate_hz == 1.0
    assert cfg.streaming.hold_log_bytes == budget.TRUTH_STORE_BYTES
    rate_hz = load_scenario(str(TINY)).imu.rate_hz
    assert cfg.streaming.chunk_samples(rate_hz) == budget.DEFAULT_CHUNK_SAMPLES
    assert load_study_config(write_study(tmp_path, file_name="none.toml")).streaming is None


def test_an_output_rate_that_does_not_divide_the_filters_is_one_error(tmp_path):
    ev = _evaluator(tmp_path, "odd", streaming={"output_rate_hz": 0.3})
    with pytest.raises(FuzzynavError, match="must be the filter's output rate") as exc:
        ev.baseline(*ev.config.train[0])
    msg = str(exc.value)  # the study file's key, not the command line's option
    assert msg.startswith("[streaming] output_rate_hz = 0.3 Hz") and "--" not in msg, msg


def test_the_held_log_estimate_bounds_a_real_log():
    """:func:`budget.held_log_bytes` against the arrays of a simulated log (an upper bound:
    the epoch columns are counted at the whole-run figure, within twice the real size)."""
    scn = load_scenario(str(TINY))
    log = simulate(scn, 0)
    held = _nbytes(log.imu) + _nbytes(log.truth) + sum(_nbytes(d) for d in log.sensors.values())
    est = budget.held_log_bytes(scn.duration_s, scn.imu.rate_hz, scn.sensors)
    assert held <= est <= 2 * held


def _nbytes(obj) -> int:
    """Bytes of the arrays of a dataclass (and of its ``meta`` dict)."""
    from dataclasses import fields

    values = [getattr(obj, f.name) for f in fields(obj)]
    values += list(getattr(obj, "meta", {}).values())
    return sum(v.nbytes for v in values if isinstance(v, np.ndarray))


def test_the_logs_a_study_holds_at_once_are_counted_together(tmp_path, monkeypatch):
    """Each tiny run fits a 100-MB limit (12 MB filtered whole, 1.2 MB held), 75 held at
    once do not; with
    ``hold_log_mb = 0`` none is held and the study is accepted."""
    scn = load_scenario(str(TINY))
    one = budget.held_log_bytes(scn.duration_s, scn.imu.rate_hz, scn.sensors)
    work = budget.whole_estimate(scn.duration_s, scn.imu.rate_hz, scn.sensors)
    limit, n = 100 * 2**20, 75
    assert work + one < limit < work + n * one  # the premise: one fits, 75 do not
    monkeypatch.setenv(budget.ENV_VAR, str(limit / 2**30))
    many = {"scenarios": [str(TINY)], "seeds": list(range(n - 2))}
    test = {"scenarios": [str(TINY)], "seeds": [100, 101]}
    path = write_study(tmp_path, file_name="held.toml", train=many, test=test)
    with pytest.raises(InputFileError) as exc:
        load_study_config(path)
    msg = exc.value.what
    assert exc.value.where == "streaming" and f"its {n} simulated runs" in msg, msg
    assert f"~{budget.human_bytes(n * one)}" in msg and "[streaming] table" in msg, msg
    path = write_study(tmp_path, file_name="all.toml", train=many, test=test,
                       streaming=CHUNKS)
    with pytest.raises(InputFileError) as exc:
        load_study_config(path)
    assert exc.value.where == "streaming.hold_log_mb" and "lower" in exc.value.what
    path = write_study(tmp_path, file_name="none.toml", train=many, test=test,
                       streaming=LONG)
    assert not load_study_config(path).streaming.holds(scn)
