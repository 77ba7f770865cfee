"""The worked example of docs/architecture.md, "Adding a local filter", as a test.

A paper's federated filter is a named filter calling :func:`bank_setup` with its sensor
groups.  Carlson's reset mode equals the centralized filter for *any* information shares
summing to 1 (``P_i = P_c / beta_i`` before each update, so ``sum P_i^-1 = P_c^-1`` whatever
the shares): with unequal shares it must still give the ``centralized`` answer.
"""
import numpy as np

from fuzzynav.filters.bank_named import bank_setup
from fuzzynav.filters.named import FilterContext, get_filter, register_filter
from fuzzynav.filters.runner import run_filter
from fuzzynav.nav import earth
from tests.filters.simple_data import run_inputs, trajectory
from tests.filters.test_bank import nhc


# a paper module would do this at import: GNSS in one local, the constraint in the other
@register_filter("test-gnss-nhc-federated", "worked example: GNSS | NHC, reset, beta 0.7/0.3")
def _example(ctx: FilterContext):
    return bank_setup(ctx, [("gnss",), ("nhc",)], "reset", beta=(0.7, 0.3))


def test_a_registered_bank_runs_and_equals_the_centralized_filter():
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, seed=7)
    ctx = FilterContext(sensors={"gnss": gnss, "nhc": nhc(tr)})
    results = {}
    for name in ("test-gnss-nhc-federated", "centralized"):
        setup = get_filter(name).make(ctx)
        results[name] = run_filter(imu, ctx.sensors, init, setup.config)
    fed, central = results["test-gnss-nhc-federated"], results["centralized"]
    assert fed.ok and fed.locals.x.shape[1] == 2
    # rounding of the information fusion only (see test_bank.py for the bound)
    d = np.array([earth.lla_to_enu(*a, *b) for a, b in zip(fed.lla, central.lla)])
    assert np.all(np.abs(d) <= 1e-6 * central.state_sigma("pos"))
    np.testing.assert_allclose(fed.sigma, central.sigma, rtol=1e-6)
    # the locals hold P_c / beta_i
    k = fed.time_s >= 1.0
    for i, beta in enumerate((0.7, 0.3)):
        np.testing.assert_allclose(fed.locals.sigma[k, i], central.sigma[k] / np.sqrt(beta),
                                   rtol=1e-6)
