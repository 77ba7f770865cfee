"""Name -> object registries (sensor kinds, measurement models, adaptation policies, filters).

A registry is a dict in registration order (the order gives the kernel ids of the compiled
loop) whose built-in modules are imported on first use, so that they register themselves;
looking up an unknown name is one clear error listing the known ones.

Two built-in modules registering the same name is a programming error (the later entry would
silently replace the earlier one), reported when the built-ins are loaded.  Registering a name
again afterwards (a notebook cell run twice, a user overriding a built-in) is allowed.

A registry may also read one module of every paper folder (``paper_module``, e.g.
``"filters"`` loads ``fuzzynav/papers/paperNNN/filters.py`` where there is one): the folders
are found by name (:func:`paper_packages`), so no generic layer imports ``fuzzynav.papers``.
"""
from __future__ import annotations

import importlib
import importlib.util
from importlib import resources

from fuzzynav.errors import FuzzynavError, UnknownNameError

__all__ = ["Registry", "paper_packages", "paper_modules", "paper_files"]


class Registry(dict):
    """A registry of ``what`` (e.g. "filter"), with built-ins in ``package.<module>``."""

    def __init__(self, what: str, package: str, builtin_modules=(), paper_module: str = ""):
        super().__init__()
        self.what = what
        self.package = package
        self.builtin_modules = tuple(builtin_modules)
        self.paper_module = paper_module
        self._loaded = False
        self._twice: list[str] = []
        self._papers: tuple = ()

    def add(self, name: str, obj):
        """Register ``obj`` under ``name`` (re-registering keeps its place); returns it."""
        if name in self and not self._loaded:
            self._twice.append(name)
        self[name] = obj
        return obj

    def load(self) -> "Registry":
        """Import the built-in modules (each registers its entries); returns self.

        Raises
        ------
        RuntimeError
            If two built-in registrations used the same name.
        """
        if not self._loaded:
            for mod in self.builtin_modules:
                importlib.import_module(f"{self.package}.{mod}")
        if self.paper_module and self._papers != paper_packages():
            for name in paper_modules(self.paper_module):  # a folder named later: next use
                importlib.import_module(name)
            self._papers = paper_packages()
        if not self._loaded:
            self._loaded = True
            if self._twice:
                raise RuntimeError(f"{self.what} names registered twice by the built-in "
                                   f"modules of {self.package}: {sorted(set(self._twice))}")
        return self

    def lookup(self, name: str):
        """The entry ``name``, or :class:`UnknownNameError` listing the known names."""
        self.load()
        try:
            return self[name]
        except KeyError:
            raise UnknownNameError(self.what, name, self) from None

    def index(self) -> dict:
        """``{name: position}`` in registration order (kernel ids)."""
        self.load()
        return {k: i for i, k in enumerate(self)}


def paper_packages() -> tuple:
    """Dotted names of the paper folders (:func:`fuzzynav.papers.paper_packages`)."""
    return importlib.import_module("fuzzynav.papers").paper_packages()


def paper_modules(module: str = "") -> list:
    """``<folder>.<module>`` of every paper folder that has that module, in folder order
    (no ``module``: the folders themselves).

    Raises
    ------
    UnknownNameError
        A paper folder (``FUZZYNAV_PAPERS``) that is not an importable package.
    """
    out = []
    for pkg in paper_packages():
        try:
            found = importlib.util.find_spec(pkg) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            raise UnknownNameError("paper folder (FUZZYNAV_PAPERS: an importable package)",
                                   pkg, paper_packages()[:5])
        if not module or importlib.util.find_spec(f"{pkg}.{module}") is not None:
            out.append(f"{pkg}.{module}" if module else pkg)
    return out


def paper_files(subdir: str, suffix: str) -> dict:
    """``{stem: file}`` of the files ``<folder>/<subdir>/*<suffix>`` of every paper folder.

    A name in two folders is an error (which of the two a script meant would be a guess).
    """
    out: dict = {}
    for pkg in paper_modules():
        folder = resources.files(pkg) / subdir
        if not folder.is_dir():
            continue
        for f in sorted(folder.iterdir(), key=lambda f: f.name):
            if not f.name.endswith(suffix):
                continue
            stem = f.name[:-len(suffix)]
            if stem in out:
                raise FuzzynavError(f"{subdir}/{f.name} is in two paper folders: "
                                    f"{out[stem]} and {f}")
            out[stem] = f
    return out
