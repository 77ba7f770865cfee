"""Name -> object registries (sensor kinds, measurement models, adaptation policies, filters).

A registry is a dict in registration order (the order gives the kernel ids of the compiled
loop) whose built-in modules are imported on first use, so that they register themselves;
looking up an unknown name is one clear error listing the known ones.

Two built-in modules registering the same name is a programming error (the later entry would
silently replace the earlier one), reported when the built-ins are loaded.  Registering a name
again afterwards (a notebook cell run twice, a user overriding a built-in) is allowed.
"""
from __future__ import annotations

import importlib

from fuzzynav.errors import UnknownNameError

__all__ = ["Registry"]


class Registry(dict):
    """A registry of ``what`` (e.g. "filter"), with built-ins in ``package.<module>``."""

    def __init__(self, what: str, package: str, builtin_modules=()):
        super().__init__()
        self.what = what
        self.package = package
        self.builtin_modules = tuple(builtin_modules)
        self._loaded = False
        self._twice: list[str] = []

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
        if self._loaded:
            return self
        for mod in self.builtin_modules:
            importlib.import_module(f"{self.package}.{mod}")
        self._loaded = True
        if self._twice:
            raise RuntimeError(f"{self.what} names registered twice by the built-in modules "
                               f"of {self.package}: {sorted(set(self._twice))}")
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
