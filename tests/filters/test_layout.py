"""Named state layouts: slices by name, today's 15- and 18-state models, the block registry."""
import math

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.error_model import ErrorModel
from fuzzynav.filters.layout import (BLOCK_KINDS, CORE, COUPLE_ACCEL, COUPLE_GYRO, COUPLE_NONE,
                                     LAYOUT_15, LAYOUT_18, N_CORE, X_ATT, X_POS, X_VEL,
                                     StateLayout, register_block)
from fuzzynav.nav import state_layout as navl


def test_slices_by_name_cover_the_state_once_in_order():
    lay = LAYOUT_18
    assert lay.n == 18
    covered = np.concatenate([np.arange(lay.n)[lay[nm]] for nm in lay.names])
    np.testing.assert_array_equal(covered, np.arange(18))
    assert lay.att == slice(0, 3) and lay.vel == slice(3, 6) and lay.pos == slice(6, 9)
    assert lay["gyro_bias:1"] == slice(12, 15) and lay["accel_bias"] == slice(15, 18)
    assert lay.sensor_slice("accel_bias") == slice(6, 9)
    assert "mag_bias" not in lay and "gyro_bias" in lay


def test_numba_constants_agree_with_the_core_layout():
    assert (X_ATT, X_VEL, X_POS, N_CORE) == (CORE.start("att"), CORE.start("vel"),
                                           CORE.start("pos"), CORE.n)


def test_todays_models_are_the_two_named_layouts():
    assert ErrorModel().layout == LAYOUT_15
    assert ErrorModel(gyro_tau_s=(math.inf, 600.0)).layout == LAYOUT_18
    start, coupling, inv_tau = ErrorModel(gyro_tau_s=(math.inf, 600.0),
                                          accel_tau_s=(1200.0,)).block_arrays()
    np.testing.assert_array_equal(start, [9, 12, 15])
    np.testing.assert_array_equal(coupling, [COUPLE_GYRO, COUPLE_GYRO, COUPLE_ACCEL])
    np.testing.assert_allclose(inv_tau, [0.0, 1 / 600.0, 1 / 1200.0])


def test_labels_name_every_state():
    labels = LAYOUT_18.labels()
    assert labels[:3] == ("phi_e", "phi_n", "phi_u") and labels[6:9] == ("dpos_e", "dpos_n",
                                                                          "dpos_u")
    assert labels[9:] == ("gyro0_x", "gyro0_y", "gyro0_z", "gyro1_x", "gyro1_y", "gyro1_z",
                          "accel0_x", "accel0_y", "accel0_z")


@pytest.mark.parametrize("blocks, match", [
    ((("vel", 3), ("att", 3), ("pos", 3)), "starts with"),
    (CORE.blocks + (("gyro_bias", 3), ("gyro_bias", 3)), "repeated"),
    (CORE.blocks + (("gyro_bias", 2),), "has 3 states"),
    (CORE.blocks + (("no_such_block", 3),), "no_such_block"),
])
def test_bad_layouts_are_refused_with_the_reason(blocks, match):
    with pytest.raises(FuzzynavError, match=match):
        StateLayout(blocks)


def test_a_bias_like_block_must_have_three_states():
    with pytest.raises(FuzzynavError, match="3 states"):
        register_block("test_bad_bias", 2, COUPLE_GYRO)
    assert "test_bad_bias" not in BLOCK_KINDS


def test_unknown_block_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError):
        LAYOUT_15.mag_bias
    with pytest.raises(KeyError, match="mag_bias"):
        LAYOUT_15["mag_bias"]


def test_config_noise_is_assembled_per_block():
    model = ErrorModel(gyro_tau_s=(math.inf, 600.0), accel_tau_s=(1200.0,))
    cfg = FilterConfig(model=model, gyro_sigma_dph=(20.0, 5.0), accel_sigma_ug=(500.0,),
                       gyro_rw_dph_psh=(0.0, 0.0), accel_rw_ug_psqrts=(0.0,))
    lay = model.layout
    p0 = np.diag(cfg.P0())
    q = cfg.q_diag()
    deg_per_h = math.pi / 180 / 3600
    np.testing.assert_allclose(p0[lay["gyro_bias:1"]], (5.0 * deg_per_h) ** 2, rtol=1e-12)
    # Gauss-Markov blocks are driven with 2 sigma^2 / tau, the random constant with nothing
    np.testing.assert_allclose(q[lay["gyro_bias:1"]], 2 * (5.0 * deg_per_h) ** 2 / 600.0,
                               rtol=1e-12)
    assert np.all(q[lay.gyro_bias] == 0.0) and np.all(q[lay.pos] == 0.0)


def test_nav_layout_slices_partition_the_nav_vector():
    idx = np.arange(navl.NAV_SIZE)
    parts = np.concatenate([idx[navl.Q_SLICE], idx[navl.VEL_SLICE], idx[navl.LLA_SLICE]])
    np.testing.assert_array_equal(np.sort(parts), idx)
    assert (navl.NAV_LAT, navl.NAV_LON, navl.NAV_H) == tuple(idx[navl.LLA_SLICE])


def test_measurement_only_kinds_do_not_couple():
    for name in ("mag_bias", "lever_arm", "dvl_scale", "dvl_misalignment", "log_scale"):
        assert BLOCK_KINDS.lookup(name).coupling == COUPLE_NONE


@pytest.mark.parametrize("noise, match", [((), r"one value per block \(1\), got 0"),
                                          (((0.0, 1.0),), r"extra_noise_si\[0\]"),
                                          (((1.0, -1.0),), r"extra_noise_si\[0\]"),
                                          (((1.0,),), r"extra_noise_si\[0\]")])
def test_extra_block_noise_is_checked_per_block(noise, match):
    cfg = FilterConfig(model=ErrorModel(extra=(("mag_bias", math.inf),)), extra_noise_si=noise)
    with pytest.raises(FuzzynavError, match=match):
        cfg.P0()


def test_noise_for_blocks_that_do_not_exist_is_refused():
    with pytest.raises(FuzzynavError, match="extra_noise_si"):
        FilterConfig(extra_noise_si=((1.0, 0.0),)).q_diag()
