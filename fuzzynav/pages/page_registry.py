"""The docs results pages: name -> generator, docs file, marked section and budgets.

A generator is a module with ``build(ctx, **budget) -> str`` returning the text of its
section (or of the whole page when the page has no marker).  ``full`` is the budget the
page's text says it was made with; ``small`` is for tests and quick looks, and is written
to another directory (``--out``), never over the docs page.
"""
from __future__ import annotations

import contextlib
import importlib
import inspect
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.pages.common import REPO_ROOT, PageContext, write_section

__all__ = ["BUDGETS", "Page", "PAGES", "get_page", "regenerate", "regenerate_parts"]

BUDGETS = ("small", "full")


@dataclass(frozen=True)
class Page:
    """One docs page that a generator (re)writes.

    Attributes
    ----------
    name : str
        The page's name on the command line (``paper000``, ``science``, ...).
    module : str
        Dotted name of the generator module.
    doc : str
        The docs file, relative to the repository root.
    marker : str or None
        The marked section (``<!-- MARKER:begin -->`` ... ``<!-- MARKER:end -->``) it
        rewrites; None: the generator writes the whole page.
    full, small : mapping
        Keyword arguments of ``build`` for the budgets ``full`` and ``small``.
    summary : str
        One line for ``fuzzynav docs list``.
    parts : mapping
        Part name -> what it is: subsections the generator module can rerun alone and
        splice into the page (its ``regenerate_parts(parts, data_dir)``), at the full budget.
    """

    name: str
    module: str
    doc: str
    marker: str | None
    full: Mapping
    small: Mapping
    summary: str
    parts: Mapping = field(default_factory=dict)


_PAPERS = "fuzzynav.papers"
PAGES = {p.name: p for p in (
    Page("paper000", f"{_PAPERS}.paper000.page", "docs/paper000.md", "results",
         {"mc": 50, "mc_variants": 20}, {"mc": 2, "mc_variants": 2},
         "paper 000 reproduced, with baselines and tuned rules"),
    Page("paper001", f"{_PAPERS}.paper001.page", "docs/paper001.md", "results",
         {"mc": 50, "mc_variants": 20}, {"mc": 2, "mc_variants": 2},
         "paper 001's federated filters and their variants"),
    Page("paper002", f"{_PAPERS}.paper002.page", "docs/paper002.md", None,
         {"mc": 50, "mc_variants": 15}, {"mc": 2, "mc_variants": 2},
         "paper 002's alignment (the whole page)"),
    Page("paper003", f"{_PAPERS}.paper003.page", "docs/paper003.md", "results",
         {"mc": 50, "mc_variants": 5}, {"mc": 2, "mc_variants": 2},
         "paper 003's polarization-aided filters and their variants"),
    Page("paper004", f"{_PAPERS}.paper004.page", "docs/paper004.md", "results",
         {"mc": 8}, {"mc": 2, "real": False},
         "paper 004 simulated and on the A-KIT recordings"),
    Page("science", "fuzzynav.pages.science", "docs/science.md", None,
         {"trials": 300, "workers": 2, "tunings": 3, "curve_trials": 1000},
         {"trials": 2, "workers": 1, "seeds": 2, "mc_recordings": 1, "recordings": False,
          "tunings": 2, "curve_trials": 4, "budgets": (1, 2, 4)},
         "the fuzzy designs against equally tuned baselines (the whole page)",
         {"split": "the car drive's held-out half, every filter tuned on its first half",
          "auv": "the A-KIT trajectories held out, both folds"}),
)}


def get_page(name: str) -> Page:
    """The page ``name``.

    Raises
    ------
    FuzzynavError
        Unknown name (the message lists the known ones).
    """
    try:
        return PAGES[name]
    except KeyError:
        raise FuzzynavError(f"unknown page {name!r}; known pages: "
                            + ", ".join(PAGES)) from None


def regenerate(page: Page, budget: str = "full", out: Path | None = None,
               root: Path = REPO_ROOT, work: Path | None = None) -> Path:
    """Run the generator of ``page`` with ``budget`` and rewrite its section.

    Parameters
    ----------
    page : Page
    budget : {"small", "full"}
    out : Path, optional
        Directory to write ``<page>.md`` (a copy of the docs page with the section
        rewritten) and its figures to; required for the small budget.  None: the docs page
        itself and ``docs/figures``.
    root : Path
        Repository root.
    work : Path, optional
        Directory for the page's study journals, so that an interrupted run resumes
        (only pages whose generator takes ``work``: the science page).

    Returns
    -------
    Path
        The file written.
    """
    if budget not in BUDGETS:
        raise FuzzynavError(f"--budget: {budget!r} is not one of {', '.join(BUDGETS)}")
    if budget != "full" and out is None:
        raise FuzzynavError(f"--budget {budget} needs --out DIR: only the full budget "
                            "rewrites the docs page")
    doc = root / page.doc
    if not doc.is_file() and page.marker is not None:
        raise FuzzynavError(f"{doc}: the docs page of {page.name!r} is missing")
    target = doc if out is None else Path(out) / doc.name
    kwargs = dict(page.full if budget == "full" else page.small)
    build = importlib.import_module(page.module).build
    if work is not None:
        if "work" not in inspect.signature(build).parameters:
            raise FuzzynavError(f"--work: page {page.name!r} runs no studies to resume")
        kwargs["work"] = str(work)
    command = f"fuzzynav docs regenerate {page.name}" + (
        "" if budget == "full" else f" --budget {budget}")
    ctx = PageContext(root=root, fig_dir=target.parent / "figures",
                      cache=Path(os.environ.get("FUZZYNAV_CACHE") or tempfile.mkdtemp()),
                      data_dir=Path(os.environ.get("FUZZYNAV_DATA",
                                                   root.parent / "shared" / "datasets")),
                      command=command)
    ctx.fig_dir.mkdir(parents=True, exist_ok=True)
    with contextlib.chdir(root):  # the generators name rules/ and studies/ files relatively
        body = build(ctx, **kwargs)
    write_section(target, page.marker, body, source=doc)
    return target



def regenerate_parts(page: Page, parts, data_dir: Path | None = None) -> Path:
    """Rerun only the named parts of ``page`` (:attr:`Page.parts`) at the full budget and
    splice them into its docs page, the rest untouched.

    Raises
    ------
    FuzzynavError
        The page has no parts, or a name is not one of them (every name is checked before
        anything runs).
    """
    if not page.parts:
        raise FuzzynavError(f"page {page.name!r} has no parts to rerun alone (--only); "
                            "pages with parts: " + ", ".join(
                                p.name for p in PAGES.values() if p.parts))
    unknown = [p for p in parts if p not in page.parts]
    if unknown or not parts:
        raise FuzzynavError(f"--only {','.join(parts)}: page {page.name!r} has the parts "
                            + ", ".join(page.parts))
    data = Path(data_dir or os.environ.get("FUZZYNAV_DATA",
                                           REPO_ROOT.parent / "shared" / "datasets"))
    with contextlib.chdir(REPO_ROOT):
        importlib.import_module(page.module).regenerate_parts(tuple(parts), data)
    return REPO_ROOT / page.doc
