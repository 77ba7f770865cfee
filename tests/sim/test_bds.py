"""BDS sensor: the GNSS model plus a constant per-axis bias (paper 001's Me, Mn, Mu)."""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters.measurements import get
from fuzzynav.sim.sensors import spec_class
from tests.sim.test_polarization import _trajectory


def _truth(n=6001):
    att = np.zeros((n, 3))
    return _trajectory(att, 100.0)


def test_bias_shifts_the_position_error_and_is_not_claimed():
    spec = spec_class("bds").from_dict({"kind": "bds", "pos_sigma_m": [2.0, 2.0, 4.0],
                                        "bias_m": [1.5, -2.0, 3.0],
                                        "bias_sigma_m": [0.0, 0.0, 0.0]}, "sensors.bds")
    d = spec.simulate(_truth(), np.random.default_rng(3))
    assert d.kind == "bds"
    err = d.meta["err_pos_enu_m"]
    # 61 fixes: the mean of the white noise is within 3 sigma / sqrt(61) of zero
    tol = 3.0 * np.array([2.0, 2.0, 4.0]) / np.sqrt(err.shape[0])
    assert np.all(np.abs(err.mean(0) - [1.5, -2.0, 3.0]) < tol)
    np.testing.assert_allclose(d.sigma[0, :3], [2.0, 2.0, 4.0])  # the receiver's own claim
    np.testing.assert_allclose(d.meta["true_sigma"][0, :3], np.hypot([2.0, 2.0, 4.0],
                                                                     [1.5, 2.0, 3.0]))


def test_random_bias_is_constant_within_a_run_and_varies_between_runs():
    spec = spec_class("bds")(pos_sigma_m=0.0, claimed_pos_sigma_m=1.0, bias_sigma_m=5.0)
    runs = [spec.simulate(_truth(), np.random.default_rng(s)).meta["err_pos_enu_m"]
            for s in range(3)]
    for err in runs:
        np.testing.assert_allclose(err, np.broadcast_to(err[0], err.shape), atol=1e-9)
    assert len({tuple(np.round(e[0], 6)) for e in runs}) == 3


def test_bds_uses_the_gnss_measurement_model():
    assert get("bds").kernel is get("gnss").kernel
    assert get("bds").channels == ("pos", "vel")


@pytest.mark.parametrize("table,key", [
    ({"bias_sigma_m": -1.0}, "sensors.b.bias_sigma_m"),
    ({"bias_m": [1.0, 2.0]}, "sensors.b.bias_m"),
    ({"bias": 1.0}, "sensors.b.bias"),
    ({"kind": "gnss"}, "sensors.b.kind"),
])
def test_bad_tables_name_the_key(table, key):
    with pytest.raises(InputFileError) as e:
        spec_class("bds").from_dict({"kind": "bds", **table}, "sensors.b")
    assert key in str(e.value)


def test_table_round_trip_keeps_the_bias():
    spec = spec_class("bds").from_dict({"kind": "bds", "bias_m": 2.0, "outages": [[10, 20]]},
                                       "s")
    assert spec_class("bds").from_dict(spec.to_dict(), "s") == spec
    assert spec.bias_m == (2.0, 2.0, 2.0)
