"""A rule file's ``binding``: how a filter feeds a fuzzy system, parsed once and checked.

The fuzzy engine carries ``binding`` as an opaque JSON object; the filters give it its
meaning here.  :meth:`Binding.of` turns it into a frozen :class:`Binding` and refuses
anything it would not use, with an :class:`~fuzzynav.errors.InputFileError` naming the
rule file and the JSON path (``$.binding.inputs.dom_pos.chanel: unknown key 'chanel';
known: statistic, channel``).  Everything downstream (packing the policy arrays, binding
to sensors, tuning) reads the dataclass, never the dict; :meth:`Binding.to_dict` writes
the same JSON back.

Keys (``docs/fuzzy.md``): ``adapter`` (a fuzzy adaptation policy), ``inputs`` (fuzzy input
-> ``statistic`` and ``channel``), ``outputs`` (fuzzy output -> the policy quantity it
drives), ``window`` (epochs, default 10), ``sensor`` (a sensor name or kind, optional),
``normalisation`` (how ``dom`` is reduced: ``relative-trace``, the only one and default),
``parent`` (a fuzzy supervisor's classical constants, e.g. ``{"b": 0.93, "floor": 0.82,
"cap": 26.8}``: the tuned parent the rules were tuned around; only for an adapter that
declares ``parent_constants``).
Statistics: the innovation ones of :mod:`~fuzzynav.filters.adaptation.window` and the
epoch-context ones of :mod:`~fuzzynav.filters.adaptation.context` (motion state, the
sensor's reported sigma, receiver quality columns).
Besides the per-sensor policies, ``adapter`` may name a filter-bank controller
(:data:`BANK_CONTROLLERS`: ``beta-sharing``, :mod:`fuzzynav.filters.beta_controller`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import MAX_QUOTE, InputFileError, brief
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import context, window

__all__ = ["WINDOW_RANGE", "DEFAULT_WINDOW", "BankController", "BANK_CONTROLLERS", "InputBinding",
           "OutputBinding", "Binding", "known_channels", "parent_constants"]

#: the DoM/ROR window in epochs, inclusive bounds
WINDOW_RANGE = (1, 10000)
DEFAULT_WINDOW = 10
_KEYS = ("adapter", "inputs", "outputs", "window", "sensor", "normalisation", "parent")
_INPUT_KEYS = ("statistic", "channel")


@dataclass(frozen=True)
class BankController:
    """A controller of a filter bank that a rule file can bind (not a per-sensor policy)."""

    name: str
    role: str
    extra_roles: tuple = ()
    domains: tuple = ()


#: bank controllers by name: ``beta-sharing`` sets the locals' information shares (a local's
#: weight, >= 0; the bank normalises the weights to shares)
BANK_CONTROLLERS = {c.name: c for c in (
    BankController("beta-sharing", "beta", domains=(("beta", 0.0, math.inf),)),)}


class _Where:
    """Raises errors located in one rule file's binding."""

    def __init__(self, source):
        self.source = source

    def error(self, where: str, what: str) -> InputFileError:
        if len(where) > MAX_QUOTE:  # a path through a long key: the message quotes it briefly
            where = f"{where[:MAX_QUOTE]}..."
        return InputFileError(self.source, "$.binding" + (f".{where}" if where else ""), what)

    def mapping(self, value, where: str, known=None) -> dict:
        """``value`` as a JSON object, with only ``known`` keys when given."""
        if not isinstance(value, dict):
            raise self.error(where, f"must be a JSON object, got {type(value).__name__}")
        for key in value:
            if known is not None and key not in known:
                at = f"{where}.{key}" if where else str(key)
                raise self.error(at, f"unknown key {brief(key)}; known: {', '.join(known)}")
        return value

    def name(self, value, where: str, what: str) -> str:
        if not isinstance(value, str) or not value:
            raise self.error(where, f"must name {what} (a non-empty string), got {brief(value)}")
        return value


@dataclass(frozen=True)
class InputBinding:
    """What feeds one fuzzy input: a windowed ``statistic`` of a measurement ``channel``."""

    name: str
    statistic: str
    channel: str = "all"


@dataclass(frozen=True)
class OutputBinding:
    """Which policy quantity (``target``, e.g. ``alpha``) a fuzzy output drives."""

    name: str
    target: str


@dataclass(frozen=True)
class Binding:
    """A parsed, checked rule-file binding (see the module docstring).

    Attributes
    ----------
    adapter : str
        Registered name of the fuzzy adaptation policy.
    inputs : tuple of InputBinding
        One per fuzzy input, in the system's input order.
    outputs : tuple of OutputBinding
    window : int
        Epochs of the innovation window.
    sensor : str or None
        Sensor name or kind to bind to (None: every sensor with the channels read).
    normalisation : str
        How ``dom`` is reduced (``relative-trace``: per channel, see
        :mod:`fuzzynav.filters.adaptation.window`).
    parent : tuple of (str, float)
        A fuzzy supervisor's classical constants (name, value), in the adapter's
        ``parent_constants`` order; empty: the parent's defaults.
    """

    adapter: str
    inputs: tuple
    outputs: tuple
    window: int = DEFAULT_WINDOW
    sensor: str | None = None
    normalisation: str = "relative-trace"
    parent: tuple = ()

    @classmethod
    def of(cls, fis, source=None, adapter: str | None = None) -> "Binding":
        """Parse and check the ``binding`` of fuzzy system ``fis`` (from file ``source``).

        With ``adapter``, the binding must name that adapter (checked first).
        """
        w = _Where(source)
        if fis.binding is None:
            raise w.error("", "missing: a rule file run by a filter needs a binding "
                              "(adapter, inputs, outputs, window)")
        doc = w.mapping(fis.binding, "", _KEYS)
        if adapter is not None and doc.get("adapter") != adapter:
            raise w.error("adapter", f"this policy needs adapter {adapter!r}; the rule file "
                                     f"is bound to {brief(doc.get('adapter'))}")
        adapter = _adapter(w, doc.get("adapter"))
        return cls(adapter=adapter.name, inputs=_inputs(w, doc.get("inputs"), fis),
                   outputs=_outputs(w, doc.get("outputs"), fis, adapter),
                   window=_window(w, doc.get("window", DEFAULT_WINDOW)),
                   sensor=None if doc.get("sensor") is None else
                   w.name(doc["sensor"], "sensor", "a sensor or sensor kind"),
                   normalisation=_normalisation(w, doc.get("normalisation", "relative-trace")),
                   parent=parent_constants(w, doc.get("parent"), adapter))

    def to_dict(self) -> dict:
        """The JSON object of this binding, as rule files write it."""
        d = {"adapter": self.adapter,
             "inputs": {b.name: {"statistic": b.statistic, "channel": b.channel}
                        for b in self.inputs},
             "outputs": {b.name: b.target for b in self.outputs},
             "window": self.window}
        if self.sensor is not None:
            d["sensor"] = self.sensor
        if any(b.statistic == "dom" for b in self.inputs):
            d["normalisation"] = self.normalisation  # says how the dom inputs are reduced
        if self.parent:
            d["parent"] = dict(self.parent)
        return d

    @property
    def channels(self) -> tuple:
        """The measurement channels read, sorted (``all`` excluded)."""
        return tuple(sorted({b.channel for b in self.inputs} - {"all"}))

    def output_index(self, fis, target: str) -> int:
        """Index in ``fis.outputs`` of the output driving ``target``."""
        name = next(b.name for b in self.outputs if b.target == target)
        return fis.output_names.index(name)

    def statistic_codes(self) -> list:
        """Kernel code of each input's statistic (:func:`window.statistic`)."""
        return [window.DOM_NORMALISATIONS[self.normalisation] if b.statistic == "dom"
                else context.STATISTICS[b.statistic] for b in self.inputs]

    def column(self, b: InputBinding, model, source=None) -> int:
        """Data-row column of the receiver-quality statistic of input ``b`` in ``model``'s
        rows (the model's ``quality``); refused when the model has no such column."""
        cols = dict(model.quality)
        if b.statistic not in cols:
            has = ", ".join(cols) or "none"
            raise _Where(source).error(
                f"inputs.{b.name}.statistic", f"the {model.kind} model carries no "
                f"{b.statistic!r} column (its quality columns: {has})")
        return cols[b.statistic]

    def check_rows(self, model, rows, source=None) -> None:
        """Refuse receiver-quality inputs whose column holds no number in data ``rows``
        (simulated GNSS has no fix type or satellite count; recordings do)."""
        for b in self.inputs:
            if b.statistic in context.QUALITY:
                col = self.column(b, model, source)
                if rows.shape[0] and not np.isfinite(rows[:, col]).any():
                    raise _Where(source).error(
                        f"inputs.{b.name}.statistic", f"the {model.kind} data carry no "
                        f"{b.statistic!r} (simulated data have none; a recording's receiver "
                        f"reports it, e.g. --data rtklib:)")

    def check_channels(self, model, source=None) -> None:
        """Refuse channels that measurement ``model`` does not have."""
        for b in self.inputs:
            if b.channel != "all" and b.channel not in model.channels:
                raise _Where(source).error(
                    f"inputs.{b.name}.channel", f"the {model.kind} model has no channel "
                    f"{brief(b.channel)} (channels: {', '.join(model.channels + ('all',))})")


def _adapter(w: _Where, name):
    name = w.name(name, "adapter", "a fuzzy adaptation policy")
    fuzzy = {k: cls for k, cls in adaptation.ADAPTERS.load().items()
             if getattr(cls, "role", "")}
    known = ", ".join(sorted(fuzzy) + [f"{c} (a filter bank's)" for c in BANK_CONTROLLERS])
    fuzzy.update(BANK_CONTROLLERS)
    if name not in fuzzy:
        raise w.error("adapter", f"unknown fuzzy adapter {brief(name)}; known: {known}")
    return fuzzy[name]


def known_channels() -> tuple:
    """Every channel of the registered measurement models, and ``all``."""
    names = {c for m in measurements.MODELS.load().values() for c in m.channels}
    return tuple(sorted(names)) + ("all",)


def _input(w: _Where, name: str, spec) -> InputBinding:
    where = f"inputs.{name}"
    spec = w.mapping(spec, where, _INPUT_KEYS)
    stat = spec.get("statistic")
    if stat not in context.STATISTICS:
        raise w.error(f"{where}.statistic", f"unknown statistic {brief(stat)}; "
                                            f"known: {', '.join(context.STATISTICS)}")
    chan = spec.get("channel", "all")
    if chan not in known_channels():
        raise w.error(f"{where}.channel", f"unknown channel {brief(chan)}; "
                                          f"known: {', '.join(known_channels())}")
    if chan != "all" and (stat in context.MOTION or stat in context.QUALITY):
        raise w.error(f"{where}.channel", f"{stat!r} is not a per-channel statistic: "
                                          f"leave channel out or write 'all'")
    return InputBinding(name, stat, chan)


def _inputs(w: _Where, doc, fis) -> tuple:
    if doc is None:
        raise w.error("inputs", "missing: map every fuzzy input to a statistic and a channel")
    doc = w.mapping(doc, "inputs")
    for name in doc:
        if name not in fis.input_names:
            raise w.error(f"inputs.{name}", f"names no input of the fuzzy system "
                                            f"(inputs: {', '.join(fis.input_names)})")
    for name in fis.input_names:
        if name not in doc:
            raise w.error(f"inputs.{name}", "missing: say which statistic feeds this input")
    return tuple(_input(w, name, doc[name]) for name in fis.input_names)


def _outputs(w: _Where, doc, fis, adapter) -> tuple:
    """One output bound to the adapter's ``role``; at most one to each of its extra roles
    (e.g. ``q_scale``, the process-noise factor of ``rq-scaling``); each output's range
    inside what its target can take (the adapter's ``domains``)."""
    role, extra = adapter.role, getattr(adapter, "extra_roles", ())
    doc = w.mapping(doc if doc is not None else {}, "outputs")
    out = []
    for name, target in doc.items():
        if name not in fis.output_names:
            raise w.error(f"outputs.{name}", f"names no output of the fuzzy system "
                                             f"(outputs: {', '.join(fis.output_names)})")
        if target != role and target not in extra:
            drives = " or ".join(repr(t) for t in (role, *extra))
            raise w.error(f"outputs.{name}", f"unknown target {brief(target)}; this adapter's "
                                             f"output drives {drives}")
        out.append(OutputBinding(name, target))
    n_role = sum(b.target == role for b in out)
    if n_role != 1 or (extra and len(out) > 1 + len(extra)):
        raise w.error("outputs", f"bind exactly one output to {role!r} (bound: {n_role})")
    if len({b.target for b in out}) != len(out):
        raise w.error("outputs", "bind at most one output to each target")
    for b in out:
        _check_domain(w, fis, b, dict((t, (lo, hi)) for t, lo, hi in adapter.domains))
    return tuple(out)


def _check_domain(w: _Where, fis, b: OutputBinding, domains: dict) -> None:
    """The kernel clamps a value outside its target's domain without a word: a range that
    leaves it is a rule file that does not do what it says."""
    if b.target not in domains:
        return
    lo, hi = domains[b.target]
    i = fis.output_names.index(b.name)
    r_lo, r_hi = fis.outputs[i].range
    if not lo <= r_lo <= r_hi <= hi:
        raise InputFileError(w.source, f"$.outputs[{i}].range",
                             f"output {b.name!r} spans [{r_lo:g}, {r_hi:g}], outside what "
                             f"{b.target!r} can take, [{lo:g}, {hi:g}] (values beyond are "
                             "clamped by the policy)")


def _window(w: _Where, n) -> int:
    lo, hi = WINDOW_RANGE
    if not isinstance(n, int) or isinstance(n, bool) or not lo <= n <= hi:
        raise w.error("window", f"must be an integer number of epochs in {lo}..{hi}, "
                                f"got {brief(n)}")
    return n


def _normalisation(w: _Where, value) -> str:
    if value not in window.DOM_NORMALISATIONS:
        raise w.error("normalisation", f"unknown normalisation {brief(value)}; known: "
                                       f"{', '.join(window.DOM_NORMALISATIONS)}")
    return value


def parent_constants(w, doc, adapter) -> tuple:
    """``binding.parent``: the tuned parent's constants as ``((name, value), ...)``, checked
    by the one reader of tuned parameters (:func:`fuzzynav.filters.params_file.check_params`,
    as the entry ``adapter.parent`` of a tuned-parameter file: every key, in range).

    ``w`` is a :class:`_Where` or a rule-file source (path or None)."""
    from fuzzynav.filters.params_file import check_params

    if doc is None:
        return ()
    w = w if isinstance(w, _Where) else _Where(w)
    parent = getattr(adapter, "parent", None)
    if parent is None:
        raise w.error("parent", f"adapter {adapter.name!r} is no fuzzy supervisor: it has no "
                                "classical parent whose constants could be set")
    return tuple(check_params(parent, doc, w.source, "$.binding.parent.").items())
