"""Named filters restricted to sensor subsets: paper 001's pairs (``centralized`` is a bank).

A subset filter is another named filter (``ekf``, ``fuzzy``, ...) run with the generic
``sensors`` option (sensor names or kinds, :func:`fuzzynav.filters.named.select_sensors`), so
the same groups can serve the local filters of a filter bank.  Paper 001 compares
SINS/BDS + polarization, SINS/BDS + magnetometer and polarization + magnetometer against the
full combination; as single filters these are the ``ekf-*`` names below, and ``fuzzy-*``
adds the magnetometer's fuzzy R-scaling (``rules/paper001_mag.json`` unless ``--rules``).
"""
from __future__ import annotations

from dataclasses import replace

from fuzzynav.filters.named import FilterContext, get_filter, register_filter

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
