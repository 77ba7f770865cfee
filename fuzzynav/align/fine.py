"""Fine alignment: a Kalman filter on the velocity of the open-loop solution.

The mechanization (:mod:`.mechanize`) runs from the coarse attitude without feedback; at
each filter epoch the filter predicts with ``Phi = expm(A T)`` (``A`` at the epoch's
attitude and mean specific force) and updates with the solution's velocity against zero
(the base does not move on average).  An optional policy rescales ``R`` before each
update: the package's one R-scaling policy, paper 002's ``R(k) = t(k) R(k-1)`` with
``t = FIS(ROR)`` (:class:`~fuzzynav.filters.adaptation.r_scaling.FuzzyRScaling`, stepped
per epoch by :class:`~fuzzynav.filters.adaptation.epoch.EpochPolicy`, the kernel the
navigation loop runs), with the alignment's bounds :data:`SCALE_BOUNDS` and ``t = 1`` until
its window is full.  ``x`` estimates the misalignment of the open-loop attitude, so the
attitude after alignment is ``(I + [phi_hat x]) C_calc``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.align.alignment_states import AlignLayout
from fuzzynav.align.model import AlignNoise, measurement_matrix, transition
from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.adaptation.epoch import EpochPolicy
from fuzzynav.filters.adaptation.r_scaling import FuzzyRScaling
from fuzzynav.filters.reference import predict, update

__all__ = ["DEFAULT_RULES", "SCALE_BOUNDS", "Epochs", "FineResult", "r_policy", "run_fine"]

#: the rule file shipped with the paper's three hand rules (ROR -> t)
DEFAULT_RULES = "paper002_ror.json"
#: epochs whose transition matrices are made at once: the Taylor series' temporaries of a
#: whole day's epochs would be ~7 kB an epoch
TRANSITION_BLOCK = 1024
#: bounds of ``tr R / tr R0`` in the alignment (the paper leaves R free; the navigation
#: loop's default floor is 1e-3)
SCALE_BOUNDS = (1e-2, 1e3)


def r_policy(rules=None) -> FuzzyRScaling:
    """The R-scaling policy of the fuzzy alignment filters.

    Parameters
    ----------
    rules : str, path or FuzzySystem, optional
        A rule file bound to the ``r-scaling`` adapter (default :data:`DEFAULT_RULES`);
        its statistics must be innovation ones (``ror``, ``dom``, ``nis``, ``trend`` of the
        velocity rows): the alignment has no motion or receiver context.
    """
    from fuzzynav.filters.catalog import find_rule_file
    from fuzzynav.fuzzy import load_fis

    fis, source = rules, None
    if not hasattr(rules, "evaluate"):
        source = str(find_rule_file(DEFAULT_RULES if rules is None else rules))
        fis = load_fis(source)
    policy = FuzzyRScaling(fis, source, scale_bounds=SCALE_BOUNDS, full_window=True)
    needs = EpochPolicy(policy, ("vel",)).needs
    if needs:
        raise FuzzynavError(f"{source or fis.name}: reads {', '.join(needs)}; the alignment "
                            "filters give only innovation statistics")
    return policy


@dataclass(frozen=True)
class Epochs:
    """The open-loop solution at the filter epochs (see :func:`.mechanize.mechanize`).

    Attributes
    ----------
    time_s : ndarray (K+1,)
    C_bn : ndarray (K+1, 3, 3)
    vel_n : ndarray (K+1, 3)
        The measurement: the solution's velocity (plus the reference's noise) [m/s].
    f_n : ndarray (K+1, 3)
        Mean specific force over the interval ending at each epoch.
    lat_rad : float
    vel_err : ndarray (K+1, 3), optional
        True velocity error of the solution (simulations only, for consistency checks).
    C_bn_true : ndarray (K+1, 3, 3), optional
        True attitude at the epochs (simulations only: the misalignment to score).
    """

    time_s: np.ndarray
    C_bn: np.ndarray
    vel_n: np.ndarray
    f_n: np.ndarray
    lat_rad: float
    vel_err: np.ndarray | None = None
    C_bn_true: np.ndarray | None = None


@dataclass(frozen=True)
class FineResult:
    """Estimates and covariances at the epochs (row 0: the prior).

    Attributes
    ----------
    time_s : ndarray (K+1,)
    x : ndarray (K+1, n)
    P : ndarray (K+1, n, n)
    r_scale : ndarray (K+1,)
        ``tr R(k) / tr R0`` used at each update (1 without a policy).
    ror : ndarray (K+1,)
        The policy's (first) statistic at each update (NaN without a policy).
    layout : AlignLayout
    """

    time_s: np.ndarray
    x: np.ndarray
    P: np.ndarray
    r_scale: np.ndarray
    ror: np.ndarray
    layout: AlignLayout

    def sigma(self, block: str) -> np.ndarray:
        """1-sigma of a block at every epoch, (K+1, size)."""
        s = self.layout[block]
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2)[:, s])

    def estimate(self, block: str) -> np.ndarray:
        """Estimates of a block at every epoch, (K+1, size)."""
        return self.x[:, self.layout[block]]


def run_fine(epochs: Epochs, layout: AlignLayout, noise: AlignNoise = AlignNoise(),
             policy=None, P0=None) -> FineResult:
    """Run the alignment filter over all epochs.

    Parameters
    ----------
    epochs : Epochs
    layout : AlignLayout
        ``LAYOUT_10`` (paper 002) or ``LAYOUT_12`` (velocity matching).
    noise : AlignNoise
        P0, Q, R0 and the period T (must match the epochs' spacing).
    policy : FuzzyRScaling, optional
        The R-scaling (:func:`r_policy`), stepped per epoch on the innovation and
        ``H P- H^T``: ``R(k) = s(k) R0``, ``s(k) = t(k) s(k-1)``.
    P0 : ndarray, optional
        Initial covariance (default ``noise.p0(layout)``), e.g. from coarse alignment.
    """
    n, K = layout.n, epochs.time_s.size - 1
    H = measurement_matrix(layout)
    R0 = noise.r0(layout)
    Qd = noise.qd(layout)
    m = H.shape[0]
    x = np.zeros(n)
    P = noise.p0(layout) if P0 is None else np.array(P0, dtype=float)
    R = R0.copy()
    x_hist, P_hist = np.zeros((K + 1, n)), np.zeros((K + 1, n, n))
    scale, ror = np.ones(K + 1), np.full(K + 1, np.nan)
    x_hist[0], P_hist[0] = x, P
    stepper = None if policy is None else EpochPolicy(policy, ("vel",) * m)
    for k in range(1, K + 1):
        j = (k - 1) % TRANSITION_BLOCK
        if j == 0:  # the next block's transitions (each epoch's alone: the same numbers)
            b = slice(k - 1, min(k - 1 + TRANSITION_BLOCK, K))
            Phis = transition(layout, epochs.C_bn[:-1][b], epochs.f_n[1:][b], epochs.lat_rad,
                              noise.period_s)
        x, P = predict(x, P, Phis[j], Qd)
        z = epochs.vel_n[k, :m]
        if stepper is not None:
            step = stepper.step(z - H @ x, H @ P @ H.T, R0)
            R = step.R
            ror[k] = step.diag[stepper.diag_names[2]]
        x, P = update(x, P, z, H, R)
        x_hist[k], P_hist[k] = x, P
        scale[k] = np.trace(R) / np.trace(R0)
    return FineResult(epochs.time_s, x_hist, P_hist, scale, ror, layout)
