"""The ``apso`` named filter: Q/R multipliers (one vocabulary) from options or a parameter file."""
import json
import math

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.classical import ConstantScale
from fuzzynav.filters.measurements import get as get_model
from fuzzynav.filters.named import FilterContext, get_filter
from fuzzynav.metrics import NavErrors, rms_metrics
from fuzzynav.sim.sensors import SensorData


def _ctx(**options):
    d = SensorData("dvl", np.zeros(1), np.zeros((1, 3)), np.full((1, 3), 0.01))
    return FilterContext(sensors={"dvl": d}, options=options)


def test_without_multipliers_it_is_the_ekf():
    a, e = get_filter("apso").make(_ctx()), get_filter("ekf").make(_ctx())
    assert not a.adapters
    np.testing.assert_allclose(a.config.q_diag(), e.config.q_diag(), rtol=1e-12)


def test_multipliers_scale_q_rows_and_r(tmp_path):
    f = tmp_path / "apso.json"
    f.write_text(json.dumps({"format": "fuzzynav-baselines",
                             "filters": {"apso": {"q_att": 4.0, "r_vel_b": 9.0}}}))
    s = get_filter("apso").make(_ctx(params=str(f), q_vel=0.25))
    e = get_filter("ekf").make(_ctx())
    lay = s.config.model.layout
    ratio = s.config.q_diag() / np.where(e.config.q_diag() > 0, e.config.q_diag(), 1.0)
    np.testing.assert_allclose(ratio[lay.att], 4.0, rtol=1e-9)
    np.testing.assert_allclose(ratio[lay.vel], 0.25, rtol=1e-9)
    ad = s.adapters["dvl"]
    assert isinstance(ad, ConstantScale)
    fp, _, _ = ad.arrays(get_model("dvl"))
    np.testing.assert_allclose(fp, [9.0])


def _params(tmp_path, apso):
    f = tmp_path / "p.json"
    f.write_text(json.dumps({"format": "fuzzynav-baselines", "filters": {"apso": apso}}))
    return str(f)


@pytest.mark.parametrize("apso,where", [({"q_att": -1}, "$.filters.apso.q_att: must be"),
                                        ({"q_bias": 2.0}, "$.filters.apso.q_bias: unknown")])
def test_bad_parameter_files_name_the_field(tmp_path, apso, where):
    with pytest.raises(InputFileError, match=where.replace("$", r"\$").replace(".", r"\.")):
        get_filter("apso").make(_ctx(params=_params(tmp_path, apso)))


@pytest.mark.parametrize("old,new", [("q_scale_att", "q_att"), ("q_scale_vel", "q_vel"),
                                     ("q_scale_gyro", "q_gyro_bias"),
                                     ("q_scale_accel", "q_accel_bias"), ("r_scale", "r_all"),
                                     ("r_scale_vel_b", "r_vel_b")])
def test_an_old_key_is_refused_naming_its_new_name(tmp_path, old, new):
    with pytest.raises(InputFileError) as exc:
        get_filter("apso").make(_ctx(params=_params(tmp_path, {old: 2.0})))
    msg = str(exc.value)
    assert f"$.filters.apso.{old}:" in msg and f"now {new!r}" in msg and "\n" not in msg
    with pytest.raises(InputFileError, match=f"options.{old}: an old name.*{new!r}"):
        get_filter("apso").make(_ctx(**{old: 2.0}))


def test_an_old_multipliers_file_is_refused_in_one_line(tmp_path):
    f = tmp_path / "old.json"
    f.write_text(json.dumps({"multipliers": {"q_scale_att": 4.0}}))
    with pytest.raises(InputFileError, match=r"\$\.multipliers: an old APSO result file"):
        get_filter("apso").make(_ctx(params=str(f)))


def test_r_all_scales_every_channel_and_a_channel_key_overrides_it():
    d = SensorData("gnss", np.zeros(1), np.zeros((1, 6)), np.full((1, 6), 1.0))
    ctx = FilterContext(sensors={"gnss": d}, options={"r_all": 3.0, "r_vel": 5.0})
    for name in ("apso", "ekf-scaled"):
        fp, _, _ = get_filter(name).make(ctx).adapters["gnss"].arrays(get_model("gnss"))
        chans = get_model("gnss").channels
        assert dict(zip(chans, fp)) == {c: 5.0 if c == "vel" else 3.0 for c in chans}, name


def test_mean_and_max_horizontal_error():
    pos = np.array([[3.0, 4.0, 9.0], [0.0, 1.0, -9.0], [6.0, 8.0, 0.0]])
    err = NavErrors(np.arange(3.0), pos, np.zeros((3, 3)), np.zeros((3, 3)))
    m = rms_metrics(err)
    assert math.isclose(m["mean_pos_h_m"], (5.0 + 1.0 + 10.0) / 3)
    assert math.isclose(m["max_pos_h_m"], 10.0)
