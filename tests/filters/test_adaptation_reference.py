"""Every adaptation policy against an independent hand computation of its published update.

Each test drives a policy's compiled kernel epoch by epoch exactly as the filter loop does
(:func:`fuzzynav.filters.loop.run_loop`: the policy's persistent state carried across
epochs, the nominal ``R`` formed afresh each epoch, buffers longer than the ``m`` rows in
use) on one short fixed innovation sequence, and compares what it returns with a plain
numpy re-implementation written here from the published equations (cited per test), not
from the kernels.  The fuzzy policies' rule files are evaluated by the engine's Python
reference path (``engine="python"``), the kernels use the compiled one.

Tolerances: the reference sums in another order (and VB works in state space where the
kernel works in measurement space), so values agree to rounding; ``RTOL`` is far below any
change a wrong update rule makes (percent, on these sequences).
"""
import numpy as np
import pytest

from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import classical
from fuzzynav.filters.adaptation.exponential_weighting import FuzzyExponentialWeighting
from fuzzynav.filters.adaptation.r_scaling import FuzzyRScaling
from fuzzynav.fuzzy import load_fis
from tests.floats import ULP_RTOL

GNSS = measurements.get("gnss")
M = 6                                   # GNSS rows: east/north/up position, then velocity
CHAN = np.array([0, 0, 0, 1, 1, 1])     # 0 = pos, 1 = vel (the model's channel order)
PAD = 2                                 # the loop's buffers are sized for its largest sensor
RTOL = 1e-10
N_STATES = 9


def _sequence(inflation):
    """One fixed innovation sequence: per epoch ``(r, H, P-, R)`` in state space.

    ``H = [I | G]`` (6 x 9) and a full ``P-`` give a full ``H P- H^T``; the innovations are
    drawn from ``N(0, H P- H^T + inflation[k] R)``: noisier, then quieter than claimed.
    """
    rng = np.random.default_rng(20261201)
    R = np.array([1.0, 1.0, 2.25, 0.04, 0.04, 0.09])        # m^2 and (m/s)^2
    out = []
    for f in inflation:
        H = np.hstack([np.eye(M), rng.normal(0.0, 0.3, (M, N_STATES - M))])
        A = rng.normal(0.0, 0.15, (N_STATES, N_STATES))
        P = A @ A.T + np.diag(rng.uniform(0.05, 0.5, N_STATES))
        HPH = H @ P @ H.T
        r = rng.multivariate_normal(np.zeros(M), HPH + f * np.diag(R))
        out.append((r, H, P, R * rng.uniform(0.8, 1.25)))     # the claim varies a little
    return out


NOISY_THEN_QUIET = [4.0] * 6 + [1.5] * 3 + [0.3] * 5             # 14 epochs
CONSISTENT_THEN_NOISY = [1.0] * 5 + [2.5] * 7 + [0.6] * 4        # 16 epochs


def drive(adapter, epochs):
    """Run ``adapter``'s kernel over ``epochs`` as the loop does: ``[(out, diag, R after)]``."""
    bound = adapter.bind(GNSS)
    fns, _ = adaptation.kernel_table()
    kernel = fns[bound.kernel_id]
    st = bound.state.copy()
    n_diag = max(adaptation.N_DIAG, len(bound.diag_names))
    got = []
    for r, H, P, R in epochs:
        # buffers longer than m, their tail holding another sensor's leftovers (NaN here):
        # a kernel must read only its m rows
        HPH = np.full((M + PAD, M + PAD), np.nan)
        HPH[:M, :M] = H @ P @ H.T
        Rbuf = np.concatenate([R, np.full(PAD, np.nan)])
        chan = np.concatenate([CHAN, np.full(PAD, 7)]).astype(np.int64)
        out, diag = np.full(2 + M + PAD, np.nan), np.zeros(n_diag)
        kernel(bound.fp, bound.ip, st, r.copy(), HPH, Rbuf, chan, M, out, diag, np.zeros(32))
        got.append((out.copy(), diag.copy(), Rbuf[:M].copy()))
    return got


def _column(got, part, index):
    return np.array([g[part][index] for g in got])


def _r_factors(got):
    return np.array([g[0][2:2 + M] for g in got])


# -- classical policies -----------------------------------------------------------------------
def sage_husa_reference(epochs, b, floor):
    """Sage & Husa (1969) with a forgetting factor, diagonal R (as in Sage-Husa AKF texts):

    ``d_k = (1 - b) / (1 - b^(k+1))`` (k = 0 at the first epoch, so ``d_0 = 1``),
    ``R_k = (1 - d_k) R_(k-1) + d_k (e_k e_k^T - H P-_k H^T)``, kept on the diagonal and floored
    at ``floor`` times the nominal variance (the usual positivity clamp).
    """
    est, factors = None, []
    for k, (r, H, P, R) in enumerate(epochs):
        d = (1.0 - b) / (1.0 - b ** (k + 1))
        prev = R if est is None else est
        est = np.maximum((1.0 - d) * prev + d * (r * r - np.diag(H @ P @ H.T)), floor * R)
        factors.append(est / R)
    return np.array(factors)


def test_sage_husa_matches_its_published_recursion():
    epochs = _sequence(NOISY_THEN_QUIET)
    got = drive(classical.SageHusa(b=0.9, floor=0.1), epochs)
    ref = sage_husa_reference(epochs, 0.9, 0.1)
    assert ref.max() > 2.0 and ref.min() < 0.5           # it adapts, both ways
    np.testing.assert_allclose(_r_factors(got), ref, rtol=RTOL)
    np.testing.assert_allclose(_column(got, 1, 0), ref[:, 0], rtol=RTOL)
    assert all(g[0][0] == 1.0 and g[0][1] == 1.0 for g in got)   # R only: P-, Q untouched


def vb_reference(epochs, rho, n_iter):
    """Särkkä & Nummenmaa (2009), IEEE TAC 54(3), Algorithm 1, diagonal R, in state space.

    Predict ``alpha- = rho alpha``, ``beta- = rho beta``; update ``alpha = alpha- + 1/2``,
    ``beta(0) = beta-``, then ``n_iter`` times: ``Sigma = diag(beta / alpha)``,
    ``K = P- H^T (H P- H^T + Sigma)^-1``, ``m = m- + K (y - H m-)``, ``P = P- - K S K^T``,
    ``beta = beta- + (y - H m)^2 / 2 + diag(H P H^T) / 2``.  The estimate is
    ``R_k = diag(beta_k / alpha_k)``; the prior is ``alpha_0 = 2``, ``beta_0 = 2 R`` (the
    module's documented choice: ``beta / alpha`` = the nominal variance).  ``m- = 0``: the
    innovation is ``y - H m-``.
    """
    alpha = beta = None
    factors = []
    for r, H, P, R in epochs:
        if alpha is None:
            alpha, beta = np.full(M, 2.0), 2.0 * R
        alpha_p, beta_p = rho * alpha, rho * beta
        alpha, beta = alpha_p + 0.5, beta_p.copy()
        for _ in range(n_iter):
            S = H @ P @ H.T + np.diag(beta / alpha)
            K = np.linalg.solve(S, H @ P).T          # P H^T S^-1 (S, P symmetric)
            m = K @ r
            P_post = P - K @ S @ K.T
            beta = beta_p + 0.5 * (r - H @ m) ** 2 + 0.5 * np.diag(H @ P_post @ H.T)
        factors.append(beta / alpha / R)
    return np.array(factors)


@pytest.mark.parametrize("n_iter", [1, 3])
def test_variational_bayes_matches_sarkka_nummenmaa(n_iter):
    epochs = _sequence(NOISY_THEN_QUIET)
    got = drive(classical.VariationalBayes(rho=0.9, iterations=n_iter), epochs)
    ref = vb_reference(epochs, 0.9, n_iter)
    assert np.ptp(ref) > 0.3                             # it adapts
    np.testing.assert_allclose(_r_factors(got), ref, rtol=RTOL)


def huber_reference(epochs, gamma):
    """Huber M-estimation, one reweighting (Huber 1964; paper 004's robust update):
    ``zeta_i = e_i / sqrt(S_ii)``, ``psi(zeta) = zeta`` for ``|zeta| <= gamma`` else
    ``gamma sign(zeta)``, weight ``w = psi(zeta) / zeta``, and ``R_ii / w_i``.
    """
    factors = []
    for r, H, P, R in epochs:
        zeta = r / np.sqrt(np.diag(H @ P @ H.T) + R)
        psi = np.where(np.abs(zeta) <= gamma, zeta, gamma * np.sign(zeta))
        factors.append(1.0 / np.where(zeta == 0.0, 1.0, psi / zeta))
    return np.array(factors)


def test_huber_matches_the_psi_function():
    epochs = _sequence(NOISY_THEN_QUIET)
    got = drive(classical.Huber(gamma=1.0), epochs)
    ref = huber_reference(epochs, 1.0)
    assert (ref == 1.0).any() and (ref > 1.5).any()        # rows on both sides of gamma
    np.testing.assert_allclose(_r_factors(got), ref, rtol=RTOL)
    np.testing.assert_allclose(_column(got, 1, 0), 1.0 / ref.max(axis=1), rtol=RTOL)


def fading_reference(epochs, rho, beta, lam_max):
    """Strong-tracking fading memory (Zhou & Frank 1996 form, as the module documents it):
    ``V_1 = e e^T``, ``V_k = (rho V_(k-1) + e e^T) / (1 + rho)`` (diagonal kept),
    ``lambda_k = min(max(1, (tr V_k - beta tr R) / tr(H P- H^T)), lam_max)`` once ``k``
    reaches the averaging length ``1 / (1 - rho)``, 1 before; ``lambda`` multiplies P-.
    """
    V, lams = None, []
    for k, (r, H, P, R) in enumerate(epochs, start=1):
        V = r * r if V is None else (rho * V + r * r) / (1.0 + rho)
        lam = (np.sum(V) - beta * np.sum(R)) / np.trace(H @ P @ H.T)
        lams.append(min(max(1.0, lam), lam_max) if k >= 1.0 / (1.0 - rho) else 1.0)
    return np.array(lams)


def test_fading_memory_matches_strong_tracking():
    epochs = _sequence(CONSISTENT_THEN_NOISY)
    got = drive(classical.FadingMemory(rho=0.75, beta=1.2, lam_max=2.0), epochs)
    ref = fading_reference(epochs, 0.75, 1.2, 2.0)
    # the settling epochs, the cap, and values between 1 and the cap all occur
    assert (ref[:3] == 1.0).all() and (ref == 2.0).any() and ((ref > 1.0) & (ref < 2.0)).sum() > 1
    np.testing.assert_allclose(_column(got, 0, 0), ref, rtol=RTOL)
    np.testing.assert_allclose(_column(got, 1, 0), ref, rtol=RTOL)
    assert (_r_factors(got) == 1.0).all()                 # P- only, R untouched


# -- fuzzy policies ---------------------------------------------------------------------------
def _window_trace(history, n, rows):
    """``tr C_r`` of ``rows``: the mean over the last ``n`` epochs of ``sum r_i^2``."""
    return float(np.mean([np.sum(r[rows] ** 2) for r in history[-n:]]))


def r_scaling_reference(fis, epochs):
    """Paper 002 (Wang et al. 2013, eqs. for the fuzzy adaptive R): ``D_r = H P- H^T + R(k-1)``,
    ``C_r = (1/N) sum_(last N) r r^T``, ``ROR(k) = tr C_r / tr D_r``, ``t(k) = FIS(ROR(k))``,
    ``R(k) = t(k) R(k-1)`` with ``R(-1)`` the nominal R; the running factor
    ``s = R(k) / R_nominal`` kept in ``[1e-3, 1e3]`` (the module's bound).
    """
    n = fis.binding["window"]
    s, history, rows = 1.0, [], []
    for r, H, P, R in epochs:
        history.append(r)
        ror = _window_trace(history, n, slice(None)) / np.trace(H @ P @ H.T + s * np.diag(R))
        t = fis.evaluate({"ror": ror}, engine="python")["t"]
        s = min(max(s * t, 1e-3), 1e3)
        rows.append((s, t, ror))
    return np.array(rows)


def _fuzzy_case(policy, rule_file, reference):
    """Drive ``policy`` bound to ``rule_file``; its diagnostics against ``reference``'s rows."""
    fis = load_fis(rule_file)
    epochs = _sequence(CONSISTENT_THEN_NOISY)
    got = drive(policy(fis, rule_file), epochs)
    ref = reference(fis, epochs)
    np.testing.assert_allclose(np.array([g[1][:ref.shape[1]] for g in got]), ref, rtol=RTOL)
    return epochs, got, ref


def _assert_every_row_scaled(got, factor):
    """Every one of the m rows of R multiplied by this epoch's ``factor``."""
    np.testing.assert_allclose(_r_factors(got), np.repeat(factor[:, None], M, axis=1), rtol=RTOL)


def test_r_scaling_matches_paper002_with_the_adapted_r_in_the_statistic():
    epochs, got, ref = _fuzzy_case(FuzzyRScaling, "rules/paper002_ror_gnss.json",
                                   r_scaling_reference)          # diag: s, t, ROR
    s, t, ror = ref.T
    # the sequence makes the running factor matter: R(k-1) departs from the nominal R by far
    # more than the tolerance, and ROR stays on the sloped part of the rule file (0 .. 2)
    assert s.min() < 0.6 and ror.max() < 2.0 and t.min() < 1.0 < t.max()
    _assert_every_row_scaled(got, s)
    for (_, _, R_after), (_, _, _, R) in zip(got, epochs):   # the loop's R is left as given
        # the kernel scales R by s for the statistic and back: (R s) / s, to rounding
        np.testing.assert_allclose(R_after, R, rtol=ULP_RTOL)


def exponential_weighting_reference(fis, epochs):
    """Paper 000 (Ren et al. 2024, eq. of the exponentially weighted KF):
    ``P- = alpha^2 Phi P Phi^T + Gamma Q Gamma^T``, ``K = P- H^T (H P- H^T + R / alpha^2)^-1``,
    ``alpha = FIS(DoM_pos, DoM_vel)`` with the degree of mismatch per channel as the module
    normalises it, ``DoM = (tr P_z - tr C_r) / tr P_z``, ``P_z = H P- H^T + R`` (the claimed R),
    ``C_r`` the window mean of ``r r^T``; ``alpha`` not below 1 (the rule file's range starts at
    1).  Returns rows ``(alpha, dom_pos, dom_vel)``.
    """
    n = fis.binding["window"]
    history, rows = [], []
    for r, H, P, R in epochs:
        history.append(r)
        Pz = np.diag(H @ P @ H.T) + R
        dom = [(Pz[c].sum() - _window_trace(history, n, c)) / Pz[c].sum()
               for c in (slice(0, 3), slice(3, 6))]
        alpha = fis.evaluate({"dom_pos": dom[0], "dom_vel": dom[1]}, engine="python")["alpha"]
        rows.append((max(alpha, 1.0), *dom))
    return np.array(rows)


def test_exponential_weighting_matches_paper000():
    _, got, ref = _fuzzy_case(FuzzyExponentialWeighting, "rules/paper000_gps_sins.json",
                              exponential_weighting_reference)   # diag: alpha, DoM pos, vel
    alpha = ref[:, 0]
    assert np.ptp(alpha) > 0.02 and (ref[:, 1:] < 0.0).any() and (ref[:, 1:] > 0.0).any()
    np.testing.assert_allclose(_column(got, 0, 0), alpha ** 2, rtol=RTOL)
    _assert_every_row_scaled(got, 1.0 / alpha ** 2)
    assert all(g[0][1] == 1.0 for g in got)               # Q is not weighted
