"""One folder per source paper: its claims, named filters and scenarios.

A paper folder ``fuzzynav/papers/paperNNN/`` holds everything specific to that paper; the
generic house (``nav``, ``fuzzy``, ``filters``, ``sim``, ``tuning``) knows nothing of it:

* ``claims.py`` registers the paper's published figures (:mod:`fuzzynav.papers.claims`);
* ``filters.py`` registers its own named filters into the one catalog
  (:func:`fuzzynav.filters.named.register_filter`);
* ``scenarios/*.toml`` are its built-in scenarios (navigation, or ``kind = "alignment"``).

Every part is optional.  The registries and the scenario lookup find the folders through
:func:`paper_packages` (loaded by name, so ``filters``/``sim`` import nothing from here):
the built-in :data:`PAPERS`, then the importable packages named in the environment variable
``FUZZYNAV_PAPERS`` (comma-separated dotted names, e.g. ``mylab.paper005``), a paper folder
kept outside this package.
"""
from __future__ import annotations

import os

#: the built-in paper folders, in the order their filters, claims and scenarios register
PAPERS = ("paper000", "paper001", "paper002", "paper003", "paper004")

#: the environment variable naming extra paper folders (importable packages)
PAPERS_ENV = "FUZZYNAV_PAPERS"


def paper_packages() -> tuple[str, ...]:
    """Dotted names of the paper folders: the built-in ones, then ``FUZZYNAV_PAPERS``'s."""
    extra = [p.strip() for p in os.environ.get(PAPERS_ENV, "").split(",") if p.strip()]
    return tuple(f"{__name__}.{p}" for p in PAPERS) + tuple(extra)
