"""Registries: built-ins load once, duplicates among them are refused, unknown names are clear."""
import sys
import types

import pytest

from fuzzynav.errors import UnknownNameError
from fuzzynav.registry import Registry


def _fake_package(monkeypatch, name, modules):
    """A package whose modules each run ``body(registry)`` when imported."""
    pkg = types.ModuleType(name)
    pkg.__path__ = []
    monkeypatch.setitem(sys.modules, name, pkg)
    for mod, body in modules.items():
        m = types.ModuleType(f"{name}.{mod}")
        m.body = body
        monkeypatch.setitem(sys.modules, f"{name}.{mod}", m)
    return pkg


def test_duplicate_builtin_names_are_refused(monkeypatch):
    reg = Registry("widget", "fakepkg_dup", ("a", "b"))
    reg.add("x", 1)
    reg.add("x", 2)      # before load: counts as a built-in registration
    _fake_package(monkeypatch, "fakepkg_dup", {"a": None, "b": None})
    with pytest.raises(RuntimeError, match=r"registered twice.*'x'"):
        reg.load()


def test_reregistering_after_load_is_allowed_and_keeps_place(monkeypatch):
    _fake_package(monkeypatch, "fakepkg_ok", {"a": None})
    reg = Registry("widget", "fakepkg_ok", ("a",))
    reg.add("x", 1)
    reg.add("y", 2)
    reg.load()
    reg.add("x", 3)
    assert reg.lookup("x") == 3
    assert reg.index() == {"x": 0, "y": 1}
    with pytest.raises(UnknownNameError):
        reg.lookup("z")


@pytest.mark.parametrize("path", [
    "fuzzynav.filters.named:FILTERS",
    "fuzzynav.filters.adaptation:ADAPTERS",
    "fuzzynav.filters.measurements:MODELS",
    "fuzzynav.sim.sensors:SENSOR_KINDS",
    "fuzzynav.filters.layout:BLOCK_KINDS",
    "fuzzynav.papers.claims:CLAIMS",
    "fuzzynav.tuning.samplers:OPTIMISERS",
])
def test_shipped_registries_have_no_duplicate_builtins(path):
    import importlib
    mod, attr = path.split(":")
    reg = getattr(importlib.import_module(mod), attr)
    reg.load()          # raises if two built-ins share a name
    assert len(reg) > 0
