"""A rule file that sets a filter bank's information shares: the ``beta-sharing`` controller.

The rule file is an ordinary fuzzy system whose ``binding`` names the adapter
``beta-sharing``; it is evaluated once per local filter at each fusion, on that local's own
innovation statistics, and its output bound to ``beta`` is the local's weight (the shares
are the normalised weights, with a floor; :mod:`fuzzynav.filters.bank_beta` derives how
they enter).  Its binding (parsed by :class:`~fuzzynav.filters.adaptation.binding.Binding`,
which refuses unknown keys) reads::

    "binding": {"adapter": "beta-sharing",
                "inputs": {"nis": {"statistic": "nis", "channel": "all"}},
                "outputs": {"w": "beta"},
                "window": 10}

* every input's ``statistic`` is ``nis`` (window mean NIS per measurement row) or ``ror``
  (window sum of ``r^T r`` over that of ``tr S``), over the local's last ``window``
  innovations; ``channel`` is ``all`` (a local may hold sensors of different channels);
* no ``sensor``: the controller belongs to the bank, not to a sensor.
"""
from __future__ import annotations

from dataclasses import dataclass

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.bank_beta import DEFAULT_FLOOR, STATISTICS, ShareControl, share_control

__all__ = ["ADAPTER", "ShareController", "is_share_controller"]

#: the ``binding.adapter`` of a share controller
ADAPTER = "beta-sharing"


@dataclass(frozen=True, eq=False)
class ShareController:
    """A fuzzy system setting the bank's shares (checked on construction).

    Parameters
    ----------
    fis : fuzzynav.fuzzy.FuzzySystem
        Its binding names the adapter ``beta-sharing`` (see the module docstring).
    source : str, optional
        The rule file (named in errors).
    floor : float
        Smallest share of a local (``0 < floor < 1 / L``; checked by the bank).
    binding : Binding, optional
        ``fis.binding`` already parsed.
    """

    fis: object
    source: str | None = None
    floor: float = DEFAULT_FLOOR
    binding: Binding | None = None

    def __post_init__(self):
        binding = self.binding
        if binding is None or binding.adapter != ADAPTER:
            binding = Binding.of(self.fis, self.source, ADAPTER)
        object.__setattr__(self, "binding", binding)
        if binding.sensor is not None:
            raise self._error("sensor", "a share controller belongs to the bank, not to a "
                                        f"sensor: remove it (got {binding.sensor!r})")
        for b in binding.inputs:
            if b.statistic not in STATISTICS:
                raise self._error(f"inputs.{b.name}.statistic",
                                  f"a share controller reads {' or '.join(STATISTICS)} over "
                                  f"its window, got {b.statistic!r}")
            if b.channel != "all":
                raise self._error(f"inputs.{b.name}.channel", "a share controller reads "
                                  f"channel 'all' (a local may mix sensors), got {b.channel!r}")
        if not isinstance(self.floor, (int, float)) or not self.floor > 0.0:
            raise InputFileError(None, "beta_floor", f"must be a share > 0, got {self.floor!r}")

    def _error(self, where: str, what: str) -> InputFileError:
        return InputFileError(self.source, f"$.binding.{where}", what)

    def share_control(self, n_local: int) -> ShareControl:
        """The loop's arrays for a bank of ``n_local`` locals."""
        cf = self.fis.compile()
        codes = tuple(STATISTICS[b.statistic] for b in self.binding.inputs)
        return share_control(n_local, cf, codes, self.binding.output_index(self.fis, "beta"),
                             self.floor, self.binding.window)


def is_share_controller(binding: Binding) -> bool:
    """Whether a parsed binding is a share controller's (not a per-sensor policy's)."""
    return binding.adapter == ADAPTER
