"""The one-way imports of docs/architecture.md, checked on the source (no import runs).

Every ``import fuzzynav...`` / ``from fuzzynav... import`` in the package — at module level
or inside a function (a function-level import dodges a cycle at import time, it does not
remove the dependency) — is an edge between two layers; an edge the layer diagram does not
allow fails.  The fuzzy engine must also be free of import cycles between its modules.
"""
from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

PKG = Path(__file__).resolve().parents[1] / "fuzzynav"

#: the foundation every layer may use
BASE = {"errors", "units", "fileio", "registry", "live_cache", "compile_notice", "fuzzynav"}
#: layer -> the layers it may import (besides itself and BASE), as docs/architecture.md draws
ALLOWED = {
    "fuzzy": set(),
    "nav": set(),
    "sim": {"nav"},
    "filters": {"fuzzy", "nav"},
    "metrics": {"nav"},
    "report": {"metrics"},
    "runpath": {"filters"},
    "experiment": {"runpath", "filters", "sim", "metrics", "nav"},
    "align": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "report", "nav"},
    "realdata": {"runpath", "filters", "sim", "metrics", "report", "nav", "plots"},
    "tuning": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "report", "nav", "plots",
               "realdata", "align"},
    "claims": {"runpath", "experiment", "filters", "sim", "metrics", "nav"},
    "plots": {"fuzzy", "nav", "metrics"},
    "cli": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "report", "nav", "tuning",
            "realdata", "claims", "plots", "align", "pages"},
    # the docs results pages: a paper's page reads its claims and runs everything
    "papers": {"pages", "runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "report",
               "nav", "tuning", "realdata", "claims", "plots", "align"},
    "pages": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "report", "nav",
              "tuning", "realdata", "claims", "plots", "align"},
    "__main__": {"cli"},
}
#: the engine is a library of its own: only the error classes of the package
FUZZY_MAY_IMPORT = {"fuzzynav.errors"}
#: known import cycles outside fuzzy/, each with the reason it is tolerated for now
CYCLE_ALLOWLIST = []


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def _resolve(base: str, name: str | None) -> str:
    """``from base import name``: the submodule when ``name`` is one, else ``base``."""
    full = f"{base}.{name}" if name else base
    return full if full in MODULES else base


def imports(module: str):
    """``(line, imported fuzzynav module)`` of every import in ``module``'s source."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "fuzzynav":
                    yield node.lineno, a.name
        elif isinstance(node, ast.ImportFrom) and node.module:
            assert node.level == 0, f"{module}:{node.lineno}: use absolute imports"
            if node.module.split(".")[0] == "fuzzynav":
                for a in node.names:
                    yield node.lineno, _resolve(node.module, a.name)


def layer(module: str) -> str:
    """``fuzzynav.filters.loop`` -> ``filters``; ``fuzzynav.units`` -> ``units``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "fuzzynav"


def graph() -> nx.DiGraph:
    g = nx.DiGraph()
    for m in MODULES:
        g.add_node(m)
        for _, target in imports(m):
            if target != m:
                g.add_edge(m, target)
    return g


def test_every_module_belongs_to_a_layer():
    unknown = {layer(m) for m in MODULES} - set(ALLOWED) - BASE
    assert not unknown, f"add these to ALLOWED and to docs/architecture.md: {unknown}"


def test_imports_go_one_way_down_the_layers():
    bad = []
    for m in MODULES:
        src = layer(m)
        if src in BASE:
            allowed = BASE
        else:
            allowed = ALLOWED[src] | BASE | {src}
        for line, target in imports(m):
            if layer(target) not in allowed:
                bad.append(f"{m}:{line} imports {target}")
    assert not bad, "imports against docs/architecture.md:\n" + "\n".join(bad)


def test_the_fuzzy_engine_imports_only_itself_and_the_errors():
    bad = [f"{m}:{line} imports {t}" for m in MODULES if layer(m) == "fuzzy"
           for line, t in imports(m)
           if layer(t) != "fuzzy" and t not in FUZZY_MAY_IMPORT]
    assert not bad, "\n".join(bad)


def test_no_import_cycles_in_fuzzy():
    g = graph().subgraph([m for m in MODULES if layer(m) == "fuzzy"])
    cycles = list(nx.simple_cycles(g))
    assert not cycles, f"import cycles among fuzzy/ modules: {cycles}"


def test_no_other_import_cycles_than_the_allowlisted():
    # strongly connected components: each tangle shows up once however many loops it has
    tangles = [c for c in nx.strongly_connected_components(graph()) if len(c) > 1]
    assert all(c in CYCLE_ALLOWLIST for c in tangles), f"import cycles: {tangles}"


def test_modules_import_no_private_names_of_each_other():
    """A name another module needs is public: ``from fuzzynav.x import _name`` fails."""
    bad = []
    for m, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module \
                    and node.module.split(".")[0] == "fuzzynav":
                bad += [f"{m}:{node.lineno} imports {node.module}.{a.name}"
                        for a in node.names
                        if a.name.startswith("_") and not a.name.startswith("__")]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("source, target, ok", [
    ("fuzzynav.filters.loop", "fuzzynav.sim.imu", False),
    ("fuzzynav.nav.earth", "fuzzynav.filters.kalman", False),
    ("fuzzynav.fuzzy.io", "fuzzynav.nav.earth", False),
    ("fuzzynav.tuning.space", "fuzzynav.filters.named", True),
])
def test_the_layer_rule_itself(source, target, ok):
    # the check above must be able to fail: known-bad edges are refused, good ones pass
    allowed = ALLOWED[layer(source)] | BASE | {layer(source)}
    assert (layer(target) in allowed) is ok
