"""Filter banks with the state-transformation error model (:func:`~fuzzynav.filters.error_st.
st_fused`, :func:`~fuzzynav.filters.error_st.st_regauge`): the locals carry ST states, the
master fuses them as they are and feeds back their phi form.

Carlson's equivalence holds in any linear coordinates of the error, so a reset bank with
equal shares fused after every update must be the centralized ST filter, as the phi bank is
the centralized phi filter (tests/filters/test_bank.py).
"""
import numpy as np

from fuzzynav.filters.bank import BankSpec
from tests.filters.test_bank import data, enu_between, run  # noqa: F401  (fixture)


def test_reset_st_bank_with_equal_shares_is_the_centralized_st_filter(data):
    # the same tolerance as the phi test: rounding in the information fusion, ~1e-10 per
    # fusion relative, damped by the filter
    central = run(data, error_model="st")
    fed = run(data, error_model="st",
              bank=BankSpec((("gnss",), ("nhc",)), (0.5, 0.5), "reset"))
    assert central.ok and fed.ok
    sig_pos, sig_vel = central.state_sigma("pos"), central.state_sigma("vel")
    assert np.all(np.abs(enu_between(fed.lla, central.lla)) <= 1e-6 * sig_pos)
    assert np.all(np.abs(fed.vel_n - central.vel_n) <= 1e-6 * sig_vel)
    np.testing.assert_allclose(fed.sigma, central.sigma, rtol=1e-6)
    # the test can fail: the ST bank is not the phi bank (the error definitions differ)
    phi = run(data, bank=BankSpec((("gnss",), ("nhc",)), (0.5, 0.5), "reset"))
    assert np.max(np.abs(phi.vel_n - central.vel_n) / sig_vel) > 1e-3


def test_no_reset_st_bank_stays_close_to_the_phi_bank(data):
    # the two error definitions linearise the same filter: with a small heading prior (the
    # linear regime) the no-reset banks agree to a small part of their sigma, and both
    # re-gauge their locals at each feedback without losing positive definiteness
    bank = BankSpec((("gnss",), ("nhc",)), (0.5, 0.5), "no-reset")
    st = run(data, error_model="st", bank=bank, init_att_sigma_deg=(0.05, 0.05, 0.1))
    phi = run(data, bank=bank, init_att_sigma_deg=(0.05, 0.05, 0.1))
    assert st.ok and phi.ok
    sig = phi.state_sigma("pos")
    assert np.max(np.abs(enu_between(st.lla, phi.lla)) / sig) < 0.1
