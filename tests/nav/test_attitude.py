"""Attitude conventions and conversions."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fuzzynav.nav import attitude as att

RNG = np.random.default_rng(3)
EUL = np.stack([RNG.uniform(-1.4, 1.4, 300), RNG.uniform(-3.1, 3.1, 300),
                RNG.uniform(0, 2 * np.pi, 300)], -1)


def test_convention_forward_axis_and_signs():
    # heading 90 deg: forward (body y) points east
    C = att.euler_to_dcm([0.0, 0.0, np.pi / 2])
    np.testing.assert_allclose(C @ [0, 1, 0], [1, 0, 0], atol=1e-15)
    # pitch up: forward gains an up component; roll positive: right wing (x) goes down
    assert att.euler_to_dcm([0.1, 0.0, 0.0])[2, 1] > 0
    assert (att.euler_to_dcm([0.0, 0.1, 0.0]) @ [1, 0, 0])[2] < 0


def test_euler_dcm_matches_scipy_intrinsic_zxy():
    # C_bn = R3(-heading) R1(pitch) R2(roll): an intrinsic z-x-y sequence
    ref = Rotation.from_euler("ZXY", np.stack([-EUL[:, 2], EUL[:, 0], EUL[:, 1]], -1)).as_matrix()
    np.testing.assert_allclose(att.euler_to_dcm(EUL), ref, atol=1e-14)


def test_round_trips():
    C = att.euler_to_dcm(EUL)
    np.testing.assert_allclose(att.dcm_to_euler(C), EUL, atol=1e-10)
    q = att.dcm_to_quat(C)
    np.testing.assert_allclose(att.quat_to_dcm(q), C, atol=1e-14)
    np.testing.assert_allclose(att.euler_to_quat(EUL), q, atol=1e-14)
    rv = att.dcm_to_rotvec(C)
    np.testing.assert_allclose(att.rotvec_to_dcm(rv), C, atol=1e-13)
    ref = Rotation.from_matrix(C).as_rotvec()
    np.testing.assert_allclose(rv, ref, atol=1e-10)


def test_quaternion_product_composes_rotations():
    q1, q2 = att.euler_to_quat(EUL[:50]), att.euler_to_quat(EUL[50:100])
    np.testing.assert_allclose(att.quat_to_dcm(att.quat_multiply(q1, q2)),
                               att.quat_to_dcm(q1) @ att.quat_to_dcm(q2), atol=1e-14)


def test_small_rotation_vectors_keep_precision():
    rv = np.array([1e-9, -2e-9, 3e-10])
    q = att.rotvec_to_quat(rv)
    np.testing.assert_allclose(att.quat_to_rotvec(q), rv, rtol=1e-12)


def test_attitude_error_definition():
    C_true = att.euler_to_dcm(EUL[:20])
    phi = RNG.normal(0, 1e-3, (20, 3))
    C_calc = (np.eye(3) - att.skew(phi)) @ C_true
    np.testing.assert_allclose(att.attitude_error(C_calc, C_true), phi, atol=1e-8)


@pytest.mark.parametrize("a,w", [(3 * np.pi, -np.pi), (-np.pi / 2, -np.pi / 2), (7.0, 7.0 - 2 * np.pi)])
def test_wrap(a, w):
    assert att.wrap_pi(a) == pytest.approx(w)
    assert 0 <= att.wrap_2pi(-0.1) < 2 * np.pi


def test_wrap_pi_one_function_for_python_and_numba():
    """The one ``wrap_pi`` agrees with numpy's floored remainder on arrays of any shape from
    Python and on scalars inside a numba kernel (two code paths: compared as angles, within
    1e-12 rad, so that a last-bit difference at the +-pi seam does not count as 2 pi)."""
    import numba as nb

    a = np.concatenate([RNG.normal(0, 20, 2000), [0.0, np.pi, -np.pi, 2 * np.pi, -7.5, 1e6]])
    ref = (a + np.pi) % (2 * np.pi) - np.pi

    def same_angle(w, r):
        assert np.all((w >= -np.pi) & (w <= np.pi))
        assert np.max(np.abs(np.angle(np.exp(1j * (w - r))))) < 1e-12

    same_angle(att.wrap_pi(a), ref)
    same_angle(att.wrap_pi(a.reshape(2, -1)).ravel(), ref)

    @nb.njit
    def wrap_each(x):
        out = np.empty_like(x)
        for i in range(x.size):
            out[i] = att.wrap_pi(x[i])
        return out

    same_angle(wrap_each(a), ref)


def test_wrap_pi_passes_nan_through_quietly():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy gives NaN for NaN without a warning: so do we
        assert np.isnan(att.wrap_pi(np.array([np.nan, 1.0]))[0])
        assert np.isnan(att.wrap_pi(np.nan))
