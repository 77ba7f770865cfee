"""Published results of the source papers, printed beside ours — never asserted in tests.

Each paper's claims live in its folder (``fuzzynav/papers/paperNNN/claims.py``), which registers a
:class:`PaperClaims` for the scenario-name prefix it covers; ``compare`` prints them beside our
Monte-Carlo results.  They come from the authors' own simulations, whose trajectories, noise and
tuning are mostly unpublished: they are references, not targets (see ../shared/seeds/DIGEST.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from fuzzynav.registry import Registry

__all__ = ["PaperClaims", "CLAIMS", "register", "find_claims", "claims_for", "rows_for"]


@dataclass(frozen=True)
class PaperClaims:
    """A paper's printed figures for the scenarios whose name starts with ``prefix``.

    Attributes
    ----------
    prefix : str
        Scenario-name prefix, e.g. ``"paper000"`` (the longest matching prefix wins).
    labels : tuple of str
        Column headers of the claimed values, e.g. ``("paper EKF (claim)", ...)``.
    table : dict
        Metric key (a column of the metrics table) -> tuple of strings, one per label.
    rows : tuple of (str, str), optional
        ``(row label, metric key)`` rows ``compare`` prints for this family; empty means the
        navigation rows of :data:`fuzzynav.report.NAV_ROWS`.
    """

    prefix: str
    labels: tuple
    table: dict
    rows: tuple = field(default=())


#: prefix -> PaperClaims; every paper folder's ``claims.py``
CLAIMS = Registry("paper claims", "fuzzynav.papers", paper_module="claims")


def register(claims: PaperClaims) -> PaperClaims:
    """Register a paper's claims under its scenario-name prefix; returns them."""
    return CLAIMS.add(claims.prefix, claims)


def find_claims(scenario_name: str):
    """The :class:`PaperClaims` of the longest prefix matching ``scenario_name``, or None."""
    CLAIMS.load()
    hits = [p for p in CLAIMS if scenario_name.startswith(p)]
    return CLAIMS[max(hits, key=len)] if hits else None


def claims_for(scenario_name: str):
    """``(labels, {metric: values})`` of the claims matching a scenario, or ``((), {})``."""
    found = find_claims(scenario_name)
    return (found.labels, found.table) if found else ((), {})


def rows_for(scenario_name: str) -> tuple:
    """The comparison rows of a scenario's family (empty: the default navigation rows)."""
    found = find_claims(scenario_name)
    return found.rows if found else ()
