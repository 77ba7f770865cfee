"""The compiled attitude chain against the numpy Hamilton product, one step at a time."""
import numpy as np

from fuzzynav.nav import attitude
from fuzzynav.nav.attitude_chain import chain, chain_into


def _increments(n, seed=0):
    rng = np.random.default_rng(seed)
    return attitude.rotvec_to_quat(rng.normal(0.0, 0.02, (n, 3)))


def test_each_step_is_the_numpy_product_of_the_last_and_the_increment():
    """Two code paths (compiled scalar loop, numpy's broadcast product): equal within
    1e-15 per component over 2 000 steps (a unit quaternion's rounding is ~1e-16 a step)."""
    dq = _increments(2000)
    q0 = attitude.rotvec_to_quat(np.array([0.3, -0.2, 1.1]))
    got = chain(q0, dq)
    prev = q0
    for k in range(dq.shape[0]):
        expected = attitude.quat_multiply(prev, dq[k])
        np.testing.assert_allclose(got[k], expected, rtol=0, atol=1e-15)
        prev = got[k]  # the same input to both for the next step: no accumulated drift


def test_the_chain_is_the_rotation_of_the_summed_increments_about_one_axis():
    """Closed form: increments about one axis compose to the rotation by their sum."""
    axis = np.array([0.6, 0.0, 0.8])
    angles = np.full(500, 0.004)
    got = chain(np.array([1.0, 0.0, 0.0, 0.0]), attitude.rotvec_to_quat(angles[:, None] * axis))
    total = attitude.rotvec_to_quat(np.cumsum(angles)[:, None] * axis)
    np.testing.assert_allclose(got, total, rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.linalg.norm(got, axis=1), 1.0, rtol=0, atol=1e-13)


def test_a_chain_carried_on_in_pieces_is_the_whole_chain():
    """Each piece started from the last attitude of the one before gives the whole chain's
    numbers to the bit (the same compiled loop on the same inputs)."""
    dq = _increments(1000, seed=1)
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    whole = chain(q0, dq)
    out = np.empty_like(whole)
    last = q0
    for a in range(0, 1000, 137):
        chain_into(last, dq[a:a + 137], out[a:a + 137])
        last = out[min(a + 137, 1000) - 1]
    assert np.array_equal(out, whole)
