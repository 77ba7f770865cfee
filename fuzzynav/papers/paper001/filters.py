"""Paper 001's named filters: its sensor pairs and its federated banks.

Subsets: paper 001 compares SINS/BDS + polarization, SINS/BDS + magnetometer and
polarization + magnetometer against the full combination; as single filters these are the
``ekf-*`` names below (another named filter run with the generic ``sensors`` option, sensor
names or kinds, :func:`fuzzynav.filters.named.select_sensors`, so the same groups serve the
local filters of a bank), and ``fuzzy-*`` adds the magnetometer's fuzzy R-scaling
(``rules/paper001_mag.json`` unless ``--rules``).

Banks: three local filters SINS/BDS, SINS/polarization, SINS/magnetometer.  The paper's
master does no filtering and keeps no information share (beta_m = 0, no-reset mode) and the
shares of the locals sum to 1; the paper does not state the three shares, so they are equal
here (1/3 each).  ``federated-p001-reset`` is the same bank in Carlson's reset mode (with
equal shares and fusion after every update it equals ``centralized``), and
``federated-fuzzy`` gives the magnetometer's local filter the fuzzy R-scaling of
``rules/paper001_mag.json`` (or the ``--rules`` given), the defence against the disturbance.
``federated-fuzzy-beta`` sets the shares at run time instead, from each local's innovations
(the share controller ``rules/paper001_beta.json``, :mod:`fuzzynav.filters.bank_beta`).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.bank_named import bank_rule_files, bank_setup
from fuzzynav.filters.catalog import bind_rule_files
from fuzzynav.filters.named import FilterContext, FilterSetup, get_filter, register_filter

__all__ = ["PAPER001_MAG_RULES", "LOCAL_GROUPS", "PAIRS", "register_subset", "PAPER001_BETA",
           "PAPER001_BETA_RULES", "p001_bank"]

#: the magnetometer controller the ``fuzzy-*`` subsets use without ``--rules``
PAPER001_MAG_RULES = "paper001_mag.json"

#: paper 001's local filters (each with the SINS as common reference), by sensor kind
LOCAL_GROUPS = (("bds",), ("polarization",), ("magnetometer",))
#: paper 001's pairs, by kind
PAIRS = {"bds-pol": ("bds", "polarization"), "bds-mag": ("bds", "magnetometer"),
         "pol-mag": ("polarization", "magnetometer")}
_WORDS = {"bds": "BDS", "polarization": "polarization", "magnetometer": "magnetometer"}


def register_subset(name: str, base: str, sensors, description: str,
                    default_options=None, takes_rules: bool = False) -> None:
    """Register ``name``: the named filter ``base`` on the sensors ``sensors`` only.

    ``default_options`` apply unless the user gives the same option (e.g. ``rules``).
    """
    defaults = dict(default_options or {})

    def make(ctx: FilterContext):
        options = {**defaults, **ctx.options, "sensors": tuple(sensors)}
        return get_filter(base).make(replace(ctx, options=options))

    register_filter(name, description, takes_rules=takes_rules)(make)


for _key, _group in PAIRS.items():
    _what = " + ".join(_WORDS[k] for k in _group)
    register_subset(f"ekf-{_key}", "ekf", _group, f"EKF with SINS/{_what} only (paper 001 pair)")
    if "magnetometer" in _group:
        register_subset(f"fuzzy-{_key}", "fuzzy", _group,
                        f"SINS/{_what} only, fuzzy R-scaling on the magnetometer "
                        f"(default rules/{PAPER001_MAG_RULES})",
                        {"rules": [PAPER001_MAG_RULES]}, takes_rules=True)

register_subset("fuzzy-mag", "fuzzy", (), "every sensor, fuzzy R-scaling on the magnetometer "
                f"(default rules/{PAPER001_MAG_RULES})", {"rules": [PAPER001_MAG_RULES]},
                takes_rules=True)


#: the paper's shares are not stated (only beta_m = 0 and sum beta_i = 1): equal
PAPER001_BETA = (1 / 3, 1 / 3, 1 / 3)
#: the share controller ``federated-fuzzy-beta`` uses without ``--rules``
PAPER001_BETA_RULES = "paper001_beta.json"


def p001_bank(ctx: FilterContext, mode: str, adapters=None, controller=None) -> FilterSetup:
    """Paper 001's bank of three locals (BDS, polarization, magnetometer) in ``mode``."""
    return bank_setup(ctx, LOCAL_GROUPS, mode, beta=PAPER001_BETA, adapters=adapters,
                      controller=controller)


def _rule_paths(ctx: FilterContext, default: str) -> list:
    given = ctx.options.get("rules") or [default]
    return [given] if isinstance(given, (str, Path)) else list(given)


@register_filter("federated-p001", "paper 001's federated filter: locals SINS/BDS, "
                                   "SINS/polarization, SINS/magnetometer, no-reset master, "
                                   "equal shares (the paper does not state them)")
def _federated_p001(ctx: FilterContext) -> FilterSetup:
    return p001_bank(ctx, "no-reset")


@register_filter("federated-p001-reset", "paper 001's three locals in reset mode (locals "
                                         "restart from the fused solution after each fusion)")
def _federated_p001_reset(ctx: FilterContext) -> FilterSetup:
    return p001_bank(ctx, "reset")


@register_filter("federated-fuzzy", "federated-p001 with fuzzy R-scaling in the magnetometer's "
                                    f"local filter (default rules/{PAPER001_MAG_RULES})",
                 takes_rules=True)
def _federated_fuzzy(ctx: FilterContext) -> FilterSetup:
    paths = _rule_paths(ctx, PAPER001_MAG_RULES)
    return p001_bank(ctx, "no-reset", bind_rule_files(paths, ctx.sensors, required=True))


@register_filter("federated-fuzzy-beta", "federated-p001 with the shares set at run time by a "
                                         "fuzzy controller of each local's innovations "
                                         f"(default rules/{PAPER001_BETA_RULES}; more --rules "
                                         "bind to the locals' sensors)", takes_rules=True)
def _federated_fuzzy_beta(ctx: FilterContext) -> FilterSetup:
    controller, adapters = bank_rule_files(_rule_paths(ctx, PAPER001_BETA_RULES), ctx)
    if controller is None:
        raise FuzzynavError("federated-fuzzy-beta: no rule file given is a share controller "
                            "(binding.adapter 'beta-sharing')")
    return p001_bank(ctx, "no-reset", adapters, controller)
