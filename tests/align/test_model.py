"""The alignment filter's transition matrix against scipy's matrix exponential."""
import numpy as np
import pytest
from scipy.linalg import expm

from fuzzynav import units
from fuzzynav.align.alignment_states import LAYOUT_10, LAYOUT_12
from fuzzynav.align.model import system_matrix, transition
from fuzzynav.nav.attitude import euler_to_dcm


@pytest.mark.parametrize("layout", [LAYOUT_10, LAYOUT_12], ids=["10", "12"])
def test_vectorised_transition_matches_expm_per_epoch(layout):
    rng = np.random.default_rng(3)
    att = rng.uniform(-0.3, 0.3, (5, 3)) + [0.0, 0.0, 1.0]
    C_bn = euler_to_dcm(att)
    f_n = np.array([0.0, 0.0, 9.8]) + rng.normal(0.0, 0.5, (5, 3))
    lat, T = 40.0 * units.DEG, 1.0
    Phis = transition(layout, C_bn, f_n, lat, T)
    assert Phis.shape == (5, layout.n, layout.n)
    for k in range(5):
        ref = expm(system_matrix(layout, C_bn[k], f_n[k], lat) * T)
        # the Taylor series is cut after the 6th power: |A T|^7/7! ~ 1e-13 relative
        np.testing.assert_allclose(Phis[k], ref, rtol=0, atol=1e-10)
        np.testing.assert_allclose(Phis[k], transition(layout, C_bn[k], f_n[k], lat, T),
                                   rtol=0, atol=1e-13)
