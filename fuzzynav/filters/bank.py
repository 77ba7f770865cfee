"""Filter banks: several local error-state filters over one shared mechanization, and a master.

A :class:`BankSpec` says which sensors each local filter processes, its information share
``beta_i`` and how the master fuses them (Carlson, "Federated square root filter for
decentralized parallel processes", IEEE TAES 26(3), 1990).  The compiled loop
(:mod:`fuzzynav.filters.loop`) runs it; the single filter is the bank of one.

What the loop does, and why
---------------------------
Every local ``i`` keeps an error state ``x_i`` and covariance ``P_i`` *about the one shared
navigation solution* ``nav`` (error = computed - true, as in the single filter), so the
local's own estimate of the truth is ``nav - x_i``.  All locals share ``F`` and ``Phi`` (one
linearisation point); local ``i`` uses the process noise ``Q / beta_i`` and starts from
``P_0 / beta_i`` (Carlson's information sharing, ``sum beta_i = 1``).

* Propagation: ``P_i <- Phi P_i Phi^T + Qd_i`` and ``x_i <- Phi x_i``.
* A measurement of a sensor of local ``i`` (the model's innovation ``z`` is formed at
  ``nav``): residual ``r = z - H x_i``, gain from ``P_i``, ``x_i <- x_i + K r``; its own
  adaptation policy and gate.  No other local changes.
* Fusion (after an accepted update, every ``fusion_period_s``; 0 = every update):
  ``P_g^-1 = sum P_i^-1``, ``x_g = P_g sum P_i^-1 x_i`` (computed on states scaled by the
  first local's standard deviations, so the inverses are of correlation-like matrices).
* Feedback of the fused estimate: ``nav <- nav - x_g`` (the single filter's feedback).  The
  error state of every local is defined about ``nav``; moving ``nav`` by ``-x_g`` moves
  every error by ``-x_g``, so ``x_i <- x_i - x_g`` and ``P_i`` is unchanged (to first
  order: the attitude correction is a rotation, composed rather than added).  Each local's
  own estimate ``nav - x_i`` is therefore untouched by the feedback: in **no-reset** mode a
  local is, to first order, the filter it would be alone with its own sensors.
* **Reset** mode then sets ``x_i <- x_g`` and ``P_i <- P_g / beta_i`` before the shift, so
  every ``x_i`` is 0 after it, as in the single filter.

Equivalences (tested in ``tests/filters/test_bank.py``)
------------------------------------------------------
* Bank of one: ``beta = 1``, ``x_g = x_1``, ``P_g = P_1``; fusion is skipped and the loop
  runs exactly the single filter's arithmetic (bit for bit).
* Reset mode fused after every update equals the centralized filter: with
  ``P_i = P_c / beta_i`` before an update, ``P_i^-1 = beta_i P_c^-1``, propagation keeps it
  (``Q_i = Q / beta_i``), and an update of local ``i`` adds ``H^T R^-1 H`` to its
  information only, so ``sum P_i^-1 = P_c^-1 + H^T R^-1 H`` and (all ``x_i = 0`` before it)
  ``x_g = P_g H^T R^-1 z``: the centralized update.  Because the feedback follows every
  update, the next measurement is linearised at the same ``nav`` as in the centralized
  filter, so this holds for the nonlinear closed-loop filter too, up to rounding in the
  inverses — *without* adaptation or gating, which read the local's ``H P_i H^T``
  (``1 / beta_i`` larger than the centralized one).
* No-reset mode: a local equals the filter run alone with its sensors and the
  ``1 / beta_i``-inflated noise, up to second-order terms in ``x_i`` (``F`` and ``H`` taken at
  ``nav`` rather than at ``nav - x_i``).

The shares may be set at run time by a fuzzy controller (:mod:`fuzzynav.filters.bank_beta`).

With the ST error model (``error_model = "st"``, :mod:`fuzzynav.filters.error_st`) the locals
carry ST states about the one ``nav``; fusion is linear in them (one ``A`` for all locals), so
the master fuses them as they are, feeds back their phi form and re-expresses ``P_g`` about
the corrected velocity (``error_st.st_fused``); a no-reset bank re-expresses every local the
same way after its shift (``x_i <- G (x_i - x_g)``, ``P_i <- G P_i G^T``,
``error_st.st_regauge``).  Reset mode fused after every update is then the centralized ST
filter (tested in ``tests/filters/test_bank_st.py``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError

__all__ = ["MODES", "BankSpec"]

MODES = ("reset", "no-reset")
MODE_RESET, MODE_NO_RESET = 1, 0
_WHERE = "bank"


@dataclass(frozen=True)
class BankSpec:
    """A bank of local filters and how the master fuses them.

    Parameters
    ----------
    locals : tuple of tuple of str
        Per local filter, the names of the sensors it processes (each sensor in one local).
    beta : tuple of float or None
        Information-sharing factors, one per local, positive and summing to 1
        (None = equal shares).
    mode : {"no-reset", "reset"}
        ``reset``: after each fusion every local restarts from the fused solution
        (``x_i = x_g``, ``P_i = P_g / beta_i``); ``no-reset``: locals keep their own.
    fusion_period_s : float
        Fuse (and feed back) at the first accepted update whose measurement time is at
        least this long after the last fusion's [s]; 0 fuses after every accepted update.
    controller : ShareController or None
        Sets the shares at run time from the locals' innovations
        (:mod:`fuzzynav.filters.bank_beta`; ``beta`` is then the initial shares); None
        keeps ``beta`` fixed.
    """

    locals: tuple
    beta: tuple | None = None
    mode: str = "no-reset"
    fusion_period_s: float = 0.0
    controller: object = None

    def __post_init__(self):
        groups = tuple(tuple(str(s) for s in g) for g in self.locals)
        object.__setattr__(self, "locals", groups)
        if not groups or any(not g for g in groups):
            raise InputFileError(None, f"{_WHERE}.locals", "needs one or more local filters, "
                                 f"each with at least one sensor, got {groups!r}")
        seen = {}
        for i, g in enumerate(groups):
            for s in g:
                if s in seen:
                    raise InputFileError(None, f"{_WHERE}.locals[{i}]",
                                         f"sensor {s!r} is already in local filter {seen[s]}; "
                                         "a sensor belongs to one local filter")
                seen[s] = i
        beta = (1.0 / len(groups),) * len(groups) if self.beta is None else \
            tuple(float(b) for b in self.beta)
        object.__setattr__(self, "beta", beta)
        if len(beta) != len(groups) or not all(math.isfinite(b) and b > 0.0 for b in beta):
            raise InputFileError(None, f"{_WHERE}.beta", f"needs one positive share per local "
                                 f"filter ({len(groups)}), got {beta!r}")
        if abs(sum(beta) - 1.0) > 1e-9:
            raise InputFileError(None, f"{_WHERE}.beta",
                                 f"information shares must sum to 1, got {sum(beta):.12g}")
        if self.mode not in MODES:
            raise InputFileError(None, f"{_WHERE}.mode", f"must be one of {', '.join(MODES)}, "
                                 f"got {self.mode!r}")
        if not (math.isfinite(self.fusion_period_s) and self.fusion_period_s >= 0.0):
            raise InputFileError(None, f"{_WHERE}.fusion_period_s",
                                 f"must be >= 0 s, got {self.fusion_period_s!r}")
        if self.controller is not None:
            self._check_controller()

    def _check_controller(self):
        if self.mode == "reset" and self.fusion_period_s <= 0.0:
            raise InputFileError(None, f"{_WHERE}.controller", "a share controller cannot act "
                                 "in reset mode fused after every update (the shares cancel "
                                 "there): use no-reset mode or a fusion_period_s > 0")
        floor = self.controller.floor
        if not 0.0 < floor * self.n_local < 1.0:
            raise InputFileError(None, f"{_WHERE}.controller.floor", f"must lie in (0, 1/"
                                 f"{self.n_local}) for {self.n_local} local filters, got "
                                 f"{floor!r}")

    @property
    def n_local(self) -> int:
        """Number of local filters."""
        return len(self.locals)

    def sensor_locals(self, names) -> np.ndarray:
        """Local-filter index of each sensor in ``names`` (the run's sensors, in loop order).

        Raises :class:`~fuzzynav.errors.InputFileError` naming a sensor of the bank the run
        does not have, or a sensor of the run no local filter processes.
        """
        index = {s: i for i, g in enumerate(self.locals) for s in g}
        names = list(names)
        for i, g in enumerate(self.locals):
            for s in g:
                if s not in names:
                    raise InputFileError(None, f"{_WHERE}.locals[{i}]", f"unknown sensor {s!r}; "
                                         f"the run's sensors: {', '.join(names) or 'none'}")
        missing = [s for s in names if s not in index]
        if missing:
            raise InputFileError(None, f"{_WHERE}.locals", f"sensor {missing[0]!r} of the run is "
                                 "in no local filter")
        return np.array([index[s] for s in names] or [0], np.int64)

    def mode_code(self) -> int:
        """:data:`MODE_RESET` or :data:`MODE_NO_RESET` (for the loop)."""
        return MODE_RESET if self.mode == "reset" else MODE_NO_RESET

