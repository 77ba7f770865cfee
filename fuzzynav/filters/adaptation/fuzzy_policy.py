"""Base class of the fuzzy adaptation policies: a rule file bound to a sensor stream."""
from __future__ import annotations

from fuzzynav.filters.adaptation import Adapter
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.adaptation.fuzzy_common import pack

__all__ = ["FuzzyPolicy"]


class FuzzyPolicy(Adapter):
    """A fuzzy system driving an adaptation, configured by its rule file's ``binding``.

    Parameters
    ----------
    fis : fuzzynav.fuzzy.FuzzySystem
        The rule set; its ``binding.adapter`` must equal the policy's ``name``.
    source : str, optional
        Where it came from (named in error messages).
    binding : Binding, optional
        ``fis.binding`` already parsed (by whoever chose this policy from it).
    """

    role = ""
    #: ``(target, lo, hi)``: the values each bound output can take (the kernel clamps
    #: beyond); a rule file whose output range leaves them is refused by its binding
    domains: tuple = ()
    diag_prefix: tuple = ()
    floats: tuple = ()

    def __init__(self, fis, source=None, binding: Binding | None = None):
        self.fis = fis
        self.source = source
        if binding is None or binding.adapter != self.name:
            binding = Binding.of(fis, source, self.name)
        self.binding = binding
        self.diag_names = tuple(self.diag_prefix) + tuple(fis.input_names)

    @property
    def channels(self) -> tuple:
        """Measurement channels the rule file reads."""
        return self.binding.channels

    def check_rows(self, model, rows) -> None:
        self.binding.check_rows(model, rows, self.source)

    def arrays(self, model):
        return pack(self.fis, self.source, self.binding, model, self.role, self.policy_floats())

    def policy_floats(self) -> tuple:
        """Extra floats of the policy (stored in ``fp[1:]``)."""
        return tuple(self.floats)
