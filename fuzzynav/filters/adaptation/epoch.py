"""One adaptation policy stepped epoch by epoch from Python: a rule file in anyone's filter.

:class:`EpochPolicy` holds a registered policy's arrays (constants, state) for one stream of
measurement rows and calls, per epoch, the very compiled kernel the filter loop calls for
that policy (taken from :func:`~fuzzynav.filters.adaptation.kernel_table` by the id its
``bind`` returns, as the loop is given it -- not ``adapter.kernel``, which an instance
turns into a bound method).  There is no second implementation: fed the loop's inputs it
returns the loop's adaptation, bit for bit (``tests/filters/test_epoch_policy.py``).

Per epoch the caller gives what the loop gives the kernel:

* ``innovation`` (m,) -- the residual; its sign does not matter to any policy (the loop
  uses *predicted minus measured*, filterpy's ``y`` is *measured minus predicted*);
* ``hph`` (m, m) -- ``H P- H^T``, the predicted covariance of the measurement *without*
  ``R`` (not filterpy's ``S``);
* ``R`` (m,) variances or an (m, m) diagonal matrix -- the nominal (unadapted) noise of this
  epoch: a running policy (``r-scaling``) keeps its factor itself;
* ``context`` -- the motion state and receiver quality a rule file's inputs may read
  (:data:`CONTEXT_KEYS`, SI units; only those the rule file binds are needed).

It returns an :class:`EpochStep`: the adapted ``R`` (same form as given), the R factors, the
covariance weight ``p_weight`` (``alpha^2`` of exponential weighting, ``lambda`` of fading
memory; the loop multiplies the part of ``P-`` propagated since the last update on the
states the measurement sees), the process-noise factor ``q_scale`` and the diagnostics.
Filter-bank controllers (``beta-sharing``: the locals' information shares) act on a bank,
not on one stream, and are refused.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import ADAPTERS, N_DIAG, Adapter, context
from fuzzynav.filters.adaptation.binding import BANK_CONTROLLERS, Binding
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy

__all__ = ["CONTEXT_KEYS", "EpochStep", "EpochPolicy"]

#: context keys -> (rule-file statistic, slot of the loop's ``ctx``); ``fix_type`` and
#: ``n_sat`` go to the measurement model's quality columns of the data row
CONTEXT_KEYS = {"speed_m_s": ("speed", context.CTX_SPEED),
                "angular_rate_rad_s": ("angular_rate", context.CTX_RATE),
                "force_deviation_m_s2": ("force_deviation", context.CTX_FORCE),
                "fix_type": ("fix_type", None), "n_sat": ("n_sat", None)}
_KEY_OF = {stat: key for key, (stat, _) in CONTEXT_KEYS.items()}
#: kernel status bits (:mod:`fuzzynav.filters.adaptation`)
CLAMPED, NO_RULE = 1, 2


@dataclass(frozen=True)
class EpochStep:
    """What a policy decided at one epoch.

    Attributes
    ----------
    R : ndarray
        The adapted variances, in the form ``R`` was given ((m,) or diagonal (m, m)).
    r_scale : (m,) ndarray
        Factor of each row's variance (adapted over given).
    p_weight : float
        Factor on the propagated part of ``P-`` (1 = none).
    q_scale : float
        Factor on the process noise from this epoch on (1 = unchanged); it compounds: the
        loop multiplies its process noise by it at every epoch (``rq-scaling`` returns the
        ratio of its new process-noise level to the previous one).
    diag : dict
        The policy's logged diagnostics by name (as in the loop's event log).
    status : int
        Kernel flags: :data:`CLAMPED` (a fuzzy input was clamped to its range),
        :data:`NO_RULE` (no rule fired).
    """

    R: np.ndarray
    r_scale: np.ndarray
    p_weight: float
    q_scale: float
    diag: dict
    status: int


class EpochPolicy:
    """A registered adaptation policy for one stream of measurement rows.

    Parameters
    ----------
    adapter : Adapter
        A registered policy instance (``adaptation.get(name)(...)``, a named filter's
        ``FilterSetup.adapters[sensor]``, or :meth:`from_rules` / :meth:`from_policy`).
    channels : sequence of str
        The measurement channel of each row, e.g. ``("pos", "pos")`` for a 2-D position fix
        (channels of ``model``; a rule file's inputs name them).
    model : str or MeasurementModel, optional
        The measurement model whose channels the rows are; default: the rule file's
        ``binding.sensor`` when it names a model, else the first registered model having
        every channel named (``gnss`` for ``pos`` / ``vel``).
    """

    def __init__(self, adapter, channels, model=None):
        ADAPTERS.load()
        name = getattr(adapter, "name", None)
        if not isinstance(adapter, Adapter) or ADAPTERS.get(name) is not type(adapter):
            raise FuzzynavError(f"EpochPolicy needs a registered adaptation policy instance, "
                                f"got {type(adapter).__name__} (registered: "
                                f"{', '.join(ADAPTERS)})")
        self.adapter = adapter
        self.channels = _channel_names(channels)
        self.model = _model(model, self.channels, getattr(adapter, "binding", None),
                            getattr(adapter, "source", None))
        self.m = len(self.channels)
        if self.m > self.model.max_rows:
            raise FuzzynavError(f"channels: {self.m} rows, the {self.model.kind} model has "
                                f"at most {self.model.max_rows}")
        self._chan = np.array([self._channel_id(c) for c in self.channels], np.int64)
        self._bound = adapter.bind(self.model)
        fns, _ = adaptation.kernel_table()
        self._kernel = fns[self._bound.kernel_id]  # the loop's kernel of this policy
        self.needs = _context_needs(getattr(adapter, "binding", None))
        cols = dict(self.model.quality)
        self._width = max(cols.values(), default=-1) + 1
        self._cols = cols
        self.reset()

    @classmethod
    def from_rules(cls, rules, channels, model=None) -> EpochPolicy:
        """The policy a rule file binds (a path, or a file name in ``rules/``)."""
        from fuzzynav.filters.catalog import find_rule_file
        from fuzzynav.fuzzy import load_fis

        path = find_rule_file(rules)
        fis = load_fis(path)
        binding = Binding.of(fis, str(path))
        if binding.adapter in BANK_CONTROLLERS:
            raise FuzzynavError(
                f"{path}: {binding.adapter!r} sets the information shares of a filter bank's "
                f"locals, not one sensor's noise; EpochPolicy steps the per-sensor policies "
                f"({', '.join(ADAPTERS)})")
        return cls(adaptation.get(binding.adapter)(fis, str(path), binding), channels, model)

    @classmethod
    def from_policy(cls, name: str, channels, model=None, **params) -> EpochPolicy:
        """A registered classical policy by name, with its parameters (e.g. ``b=0.97``)."""
        kind = adaptation.get(name)
        if issubclass(kind, FuzzyPolicy):
            raise FuzzynavError(f"{name!r} is run by a rule file: use "
                                f"EpochPolicy.from_rules(path, channels)")
        try:
            adapter = kind(**params)
        except TypeError as e:
            raise FuzzynavError(f"{name}: bad parameters {sorted(params)}: {e}") from None
        return cls(adapter, channels, model)

    @property
    def name(self) -> str:
        """The policy's registered name."""
        return self.adapter.name

    @property
    def diag_names(self) -> tuple:
        """Names of the diagnostics :meth:`step` returns."""
        return self._bound.diag_names

    @property
    def state(self) -> np.ndarray:
        """A copy of the policy's running state (windows, estimates)."""
        return self._state.copy()

    def reset(self) -> None:
        """Forget every epoch seen: back to the state the loop starts a run with."""
        self._state = self._bound.state.copy()
        self._diag = np.zeros(N_DIAG)

    def step(self, innovation, hph, R, context=None) -> EpochStep:
        """Adapt one epoch (see the module docstring for the arguments)."""
        r = self._vector(innovation, "innovation")
        HPH = _floats(hph, "hph")
        if self.m == 1 and HPH.size == 1:
            HPH = HPH.reshape(1, 1)
        if HPH.shape != (self.m, self.m) or not np.isfinite(HPH).all():
            raise FuzzynavError(f"hph: must be a finite ({self.m}, {self.m}) array "
                                f"(H P- H^T of the {self.m} rows), got shape {HPH.shape}")
        R_in = _floats(R, "R")
        Rv = self._variances(R_in)
        ctx = self._context(context, Rv)
        out = np.ones(2 + self.m)
        Rk = Rv.copy()  # the kernel may round-trip R in place: the loop scales what it leaves
        status = self._kernel(self._bound.fp, self._bound.ip, self._state, r, HPH, Rk,
                              self._chan, self.m, out, self._diag, ctx)
        scale = out[2:].copy()
        Ra = Rk * scale
        return EpochStep(R=np.diag(Ra) if R_in.ndim == 2 else Ra, r_scale=scale,
                         p_weight=float(out[0]), q_scale=float(out[1]),
                         diag={k: float(v) for k, v in zip(self.diag_names, self._diag)},
                         status=int(status))

    # -- checks -------------------------------------------------------------------------
    def _channel_id(self, name: str) -> int:
        if name == "all":
            raise FuzzynavError("channels: 'all' is not a row's channel; name each row's "
                                f"channel ({', '.join(self.model.channels)})")
        return self.model.channel_index(name)

    def _vector(self, value, what: str) -> np.ndarray:
        """``value`` as m finite floats: (m,), a column (m, 1) or, for one row, a scalar."""
        v = _floats(value, what)
        if v.shape in ((self.m, 1), () if self.m == 1 else (self.m,)):
            v = v.reshape(self.m)
        if v.shape != (self.m,) or not np.isfinite(v).all():
            raise FuzzynavError(f"{what}: must be {self.m} finite values (one per row of "
                                f"{self.channels}), got {np.shape(value)} {value!r}"[:200])
        return v

    def _variances(self, R: np.ndarray) -> np.ndarray:
        if R.ndim == 2:
            if R.shape != (self.m, self.m) or np.any(R[~np.eye(self.m, dtype=bool)] != 0.0):
                raise FuzzynavError(f"R: must be ({self.m},) variances or a diagonal "
                                    f"({self.m}, {self.m}) matrix (the policies adapt a "
                                    f"diagonal R), got shape {R.shape}")
            R = np.diag(R)
        Rv = self._vector(R, "R")
        if np.any(Rv <= 0.0):
            raise FuzzynavError(f"R: variances must be positive, got {Rv}")
        return Rv

    def _context(self, given, Rv) -> np.ndarray:
        """The loop's ``ctx`` for this epoch: motion state, nominal R, quality columns."""
        given = dict(given or {})
        unknown = sorted(set(given) - set(CONTEXT_KEYS))
        if unknown:
            raise FuzzynavError(f"context: unknown key(s) {', '.join(unknown)}; known: "
                                f"{', '.join(CONTEXT_KEYS)}")
        missing = [k for k in self.needs if k not in given]
        if missing:
            raise FuzzynavError(f"context: the rule file {self.adapter.source} reads "
                                f"{', '.join(missing)}; give them per epoch")
        ctx = np.full(context.size(self.m, self._width), np.nan)
        ctx[context.CTX_M] = self.m
        ctx[context.CTX_R:context.CTX_R + self.m] = Rv
        for key, value in given.items():
            value = float(value)
            if not np.isfinite(value):
                raise FuzzynavError(f"context: {key} must be a finite number, got {value}")
            stat, slot = CONTEXT_KEYS[key]
            if slot is None:
                if stat not in self._cols:
                    raise FuzzynavError(f"context: the {self.model.kind} model has no "
                                        f"{stat!r} column")
                slot = context.CTX_R + self.m + self._cols[stat]
            ctx[slot] = value
        return ctx


def _floats(value, what: str) -> np.ndarray:
    """``value`` as a new float array (one clear error when it holds no numbers)."""
    try:
        return np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise FuzzynavError(f"{what}: must be numbers, got {value!r}"[:200]) from None


def _channel_names(channels) -> tuple:
    names = (channels,) if isinstance(channels, str) else tuple(channels)
    if not names or not all(isinstance(c, str) for c in names):
        raise FuzzynavError(f"channels: name the measurement channel of each row (strings), "
                            f"got {channels!r}")
    return names


def _model(model, channels, binding, source=None):
    """The measurement model the rows belong to (see :class:`EpochPolicy`)."""
    models = measurements.MODELS.load()
    if isinstance(model, str):
        model = measurements.get(model)
    if model is None and binding is not None and binding.sensor in models:
        model = models[binding.sensor]
    wanted = set(channels) | set(binding.channels if binding is not None else ())
    wanted.discard("all")
    if model is None:
        model = next((m for m in models.values() if wanted <= set(m.channels)), None)
        if model is None:
            raise FuzzynavError(f"channels: no measurement model has all of "
                                f"{sorted(wanted)}; known: " + "; ".join(
                                    f"{k} ({', '.join(m.channels)})" for k, m in models.items()))
    if binding is not None:
        binding.check_channels(model, source)
    return model


def _context_needs(binding) -> tuple:
    """Context keys a rule file's inputs read."""
    if binding is None:
        return ()
    return tuple(dict.fromkeys(_KEY_OF[b.statistic] for b in binding.inputs
                               if b.statistic in _KEY_OF))
