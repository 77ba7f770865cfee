"""The ``apso`` named filter: Q/R multipliers from options or a result file."""
import json
import math

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.classical import ConstantScale
from fuzzynav.filters.measurements import get as get_model
from fuzzynav.filters.named import FilterContext, get_filter
from fuzzynav.filters.tuned_qr import read_multipliers
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
    f.write_text(json.dumps({"multipliers": {"q_scale_att": 4.0, "r_scale_vel_b": 9.0}}))
    s = get_filter("apso").make(_ctx(apso_file=str(f), q_scale_vel=0.25))
    e = get_filter("ekf").make(_ctx())
    lay = s.config.model.layout
    ratio = s.config.q_diag() / np.where(e.config.q_diag() > 0, e.config.q_diag(), 1.0)
    np.testing.assert_allclose(ratio[lay.att], 4.0, rtol=1e-9)
    np.testing.assert_allclose(ratio[lay.vel], 0.25, rtol=1e-9)
    ad = s.adapters["dvl"]
    assert isinstance(ad, ConstantScale)
    fp, _, _ = ad.arrays(get_model("dvl"))
    np.testing.assert_allclose(fp, [9.0])


@pytest.mark.parametrize("doc,where", [({"multipliers": {"q_scale_att": -1}}, "q_scale_att"),
                                       ({"multipliers": {"q_att": 2.0}}, "q_att"),
                                       ({"other": 1}, "multipliers")])
def test_bad_result_files_name_the_field(tmp_path, doc, where):
    f = tmp_path / "bad.json"
    f.write_text(json.dumps(doc))
    with pytest.raises(InputFileError, match=where):
        read_multipliers(f)


def test_mean_and_max_horizontal_error():
    pos = np.array([[3.0, 4.0, 9.0], [0.0, 1.0, -9.0], [6.0, 8.0, 0.0]])
    err = NavErrors(np.arange(3.0), pos, np.zeros((3, 3)), np.zeros((3, 3)))
    m = rms_metrics(err)
    assert math.isclose(m["mean_pos_h_m"], (5.0 + 1.0 + 10.0) / 3)
    assert math.isclose(m["max_pos_h_m"], 10.0)
