"""``align-kf-tuned``: paper 002's alignment KF with constant tuned multipliers.

Checked against ``align-kf`` (multipliers 1: bit for bit), against a Kalman filter written
out here with ``R = c R0`` and the scaled Q rows (not the package's run_fine), against the
scale invariance of the Kalman filter (P0, Q and R all times c: same estimates, P times c),
and for one clear error per bad parameter file; then the alignment study that tunes it."""
import json

import numpy as np
import pytest

from fuzzynav.align import alignment_run as R
from fuzzynav.align.fine import run_fine
from fuzzynav.align.model import measurement_matrix, transition
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.align.tune import Runs
from fuzzynav.align.tuned import NAME, scaled_noise, tuned_params
from fuzzynav.cli import main
from fuzzynav.errors import FuzzynavError, InputFileError
from tests.align.test_tuned_rules import SHORT  # the short alignment scenario of the studies



@pytest.fixture(scope="module")
def run():
    scn = load_alignment_scenario("paper002-rmismatch")
    log = R.simulate(scn, 4)
    return scn, log, R.epochs(scn, log, 4)


def _file(tmp_path, params, name=NAME):
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"format": "fuzzynav-baselines", "version": 1,
                                "filters": {name: params}}))
    return path


def test_multipliers_of_one_are_align_kf_bit_for_bit(run, tmp_path):
    scn, log, ep = run
    plain = R.run_align_filter("align-kf", scn, log, ep)
    path = _file(tmp_path, {"r_all": 1, "q_vel": 1.0, "q_att": 1.0})
    for tuned in (R.run_align_filter(f"{NAME}@{path}", scn, log, ep),
                  R.run_align_filter(NAME, scn, log, ep, params={"r_all": 1.0})):
        assert np.array_equal(tuned.result.x, plain.result.x)
        assert np.array_equal(tuned.result.P, plain.result.P)
        assert np.array_equal(tuned.phi_hat, plain.phi_hat)
        assert R.metrics(tuned, 10.0) == R.metrics(plain, 10.0)


def _reference_kf(ep, noise, layout, R_meas, Qd):
    """The textbook KF (standard covariance update), written out independently."""
    H = measurement_matrix(layout)
    Phis = transition(layout, ep.C_bn[:-1], ep.f_n[1:], ep.lat_rad, noise.period_s)
    x, P = np.zeros(layout.n), noise.p0(layout)
    xs = [x]
    for k in range(1, ep.time_s.size):
        x, P = Phis[k - 1] @ x, Phis[k - 1] @ P @ Phis[k - 1].T + Qd
        S = H @ P @ H.T + R_meas
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (ep.vel_n[k, :H.shape[0]] - H @ x)
        P = (np.eye(layout.n) - K @ H) @ P
        xs.append(x)
    return np.array(xs), P


def test_multiplier_c_is_the_kf_with_c_times_r0_and_scaled_q_rows(run):
    scn, log, ep = run
    spec = R.get_align_filter(NAME)
    c, qv, qa = 7.5, 2.0, 0.3
    got = R.run_align_filter(NAME, scn, log, ep, params={"r_all": c, "q_vel": qv, "q_att": qa})
    L = spec.layout
    Qd = scn.noise.qd(L).copy()
    # Q0 per row: the velocity rows scale by q_vel, the attitude rows by q_att
    rows = np.ones(L.n)
    rows[L.vel], rows[L.att] = qv, qa
    x_ref, P_ref = _reference_kf(ep, scn.noise, L, c * scn.noise.r0(L), Qd * rows[:, None])
    assert np.allclose(got.result.x, x_ref, rtol=1e-7, atol=1e-12 * np.abs(x_ref).max())
    assert np.allclose(got.result.P[-1], P_ref, rtol=1e-6, atol=1e-20)
    # and it is not align-kf: the multipliers change the estimate
    plain = R.run_align_filter("align-kf", scn, log, ep)
    assert not np.allclose(got.result.x, plain.result.x, rtol=1e-3)


def test_scaling_p0_q_and_r_together_leaves_the_estimate_and_scales_p(run):
    scn, _, ep = run
    L = R.get_align_filter(NAME).layout
    c = 16.0
    base = run_fine(ep, L, scn.noise)
    both = run_fine(ep, L, scaled_noise(scn.noise, {"r_all": c, "q_vel": c, "q_att": c}),
                    P0=c * scn.noise.p0(L))
    assert np.allclose(both.x, base.x, rtol=1e-9, atol=1e-15)
    assert np.allclose(both.P, c * base.P, rtol=1e-9, atol=1e-24)


@pytest.mark.parametrize("params, field, words", [
    ({"r_all": -1.0}, "$.filters.align-kf-tuned.r_all", "must be a number in [1e-06, 1e+06]"),
    ({"r_vel": 2.0}, "$.filters.align-kf-tuned.r_vel", "unknown parameter of align-kf-tuned"),
    ({}, "$.filters.align-kf-tuned", "is empty"),
    ({"q_att": "big"}, "$.filters.align-kf-tuned.q_att", "must be a number"),
])
def test_a_bad_parameter_file_gives_one_error_naming_file_and_field(tmp_path, params, field,
                                                                    words):
    path = _file(tmp_path, params)
    with pytest.raises(InputFileError) as err:
        tuned_params(path)
    msg = str(err.value)
    assert str(path) in msg and field in msg and words in msg and "\n" not in msg


def test_a_file_without_the_filter_names_the_missing_entry(tmp_path):
    path = _file(tmp_path, {"b": 0.9, "floor": 0.1, "cap": 10.0}, name="sage-husa-tuned")
    with pytest.raises(InputFileError, match=r"\$\.filters\.align-kf-tuned: missing"):
        tuned_params(path)


def test_the_cli_refuses_a_bad_file_in_one_line(tmp_path, capsys):
    path = _file(tmp_path, {"q_vel": 0.0})
    code = main(["compare", "paper002", "--filters", f"align-kf,{NAME}@{path}", "--mc", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "$.filters.align-kf-tuned.q_vel" in err and err.count("\n") == 1
    with pytest.raises(FuzzynavError, match="align-kf takes no rule file"):
        R.align_spec(f"align-kf@{path}")
    with pytest.raises(FuzzynavError, match="no tuned-parameter file after '@'"):
        R.align_spec(f"{NAME}@")


def test_the_study_writes_a_parameter_file_that_scores_what_it_reported(tmp_path, capsys):
    scn = tmp_path / "short.toml"
    scn.write_text(SHORT)
    cfg = tmp_path / "base.toml"
    body = f'''filter = "{NAME}"
kind = "alignment"
output = "tuned.json"
n_trials = 3
sampler_seed = 2
train = ["{scn}"]
train_seeds = [0, 1]
test = []
'''
    cfg.write_text(body)
    assert main(["study", "run", str(cfg)]) == 0
    out = capsys.readouterr().out
    summary = json.loads(out[:out.rindex("wrote ")])
    params = tuned_params(tmp_path / "tuned.json")
    assert params == pytest.approx(summary["best_params"], rel=0)
    doc = json.loads((tmp_path / "tuned.json").read_text())
    assert doc["trials"] == {NAME: 3}
    assert doc["train_score"][NAME] == summary["train"]["tuned"]
    # re-scored independently of the study: the file's filter on the training runs
    train = Runs([(str(scn), 0), (str(scn), 1)])
    rescored, _ = train.score(None, f"{NAME}@{tmp_path / 'tuned.json'}", 1.0)
    assert rescored == pytest.approx(summary["train"]["tuned"], rel=1e-12)
    plain, _ = train.score(None, "align-kf", 1.0)
    assert summary["train"]["align-kf"] == pytest.approx(plain, rel=1e-12)
    # a constant study takes no rule template
    cfg.write_text(body + 'template = "x.json"\n')
    assert main(["study", "run", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert str(cfg) in err and "template" in err and "not read by an align-kf-tuned" in err
