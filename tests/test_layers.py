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
BASE = {"errors", "units", "fileio", "registry", "live_cache", "compile_notice", "block_sums",
        "fuzzynav"}
#: layer -> the layers it may import (besides itself and BASE), as docs/architecture.md draws
ALLOWED = {
    "fuzzy": set(),
    "nav": set(),
    "sim": {"nav"},
    "filters": {"fuzzy", "nav"},
    "metrics": {"nav"},
    "metrics_rscale": set(),  # the metrics layer: usage of a sensor's R
    "metrics_segments": {"metrics"},  # the metrics layer: errors per motion segment
    "report": {"metrics"},
    "runpath": {"filters", "sim", "chunk_feed"},  # sim.budget: the memory a run's outputs need
    "chunk_feed": {"sim"},  # sim.stream.epochs_between: a chunk's epochs as a simulation's
    "experiment": {"runpath", "filters", "sim", "metrics", "metrics_rscale", "metrics_segments", "nav", "simsource",
                   "streamrun"},
    # a simulated log as a run source (context, initial error): whole or streamed
    "simsource": {"filters", "sim", "nav"},
    # a run on a scenario simulated chunk by chunk (under experiment, which dispatches to it)
    "streamrun": {"simsource", "runpath", "filters", "sim", "metrics", "metrics_rscale", "metrics_segments",
                  "streamtrace"},
    # what a streamed run keeps for its figures (errors of the kept rows, thinned events)
    "streamtrace": {"filters", "metrics"},
    "align": {"runpath", "experiment", "streamrun", "filters", "fuzzy", "sim", "metrics",
              "metrics_rscale", "report", "nav"},
    "realdata": {"runpath", "filters", "sim", "metrics", "metrics_rscale", "metrics_segments", "report", "nav", "plots"},
    "tuning": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "metrics_rscale", "metrics_segments", "report", "nav", "plots",
               "realdata", "align"},
    # a paper folder: its claims, filters and scenarios, and its results page (which runs
    # everything: studies, recordings, figures)
    "papers": {"pages", "runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "metrics_rscale", "metrics_segments", "report",
               "nav", "tuning", "realdata", "plots", "align"},
    "plots": {"fuzzy", "nav", "metrics"},
    "cli": {"runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "metrics_rscale", "metrics_segments", "report", "nav", "tuning",
            "realdata", "papers", "plots", "align", "pages"},
    "pages": {"papers", "runpath", "experiment", "filters", "fuzzy", "sim", "metrics", "metrics_rscale", "metrics_segments", "report",
              "nav", "tuning", "realdata", "plots", "align"},
    "__main__": {"cli"},
}
#: the engine is a library of its own: only the error classes of the package and its one
#: atomic writer (which keeps every file out of system directories), nothing of navigation
FUZZY_MAY_IMPORT = {"fuzzynav.errors", "fuzzynav.fileio"}
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


def test_the_fuzzy_engine_imports_only_itself_the_errors_and_the_writer():
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
    ("fuzzynav.sim.scenario", "fuzzynav.realdata.loaders.rtklib", False),
    ("fuzzynav.realdata.loaders.rtklib", "fuzzynav.sim.imu", True),
])
def test_the_layer_rule_itself(source, target, ok):
    # the check above must be able to fail: known-bad edges are refused, good ones pass
    allowed = ALLOWED[layer(source)] | BASE | {layer(source)}
    assert (layer(target) in allowed) is ok


#: module names shared by design: a sensor kind's simulator and its measurement model
PAIRED_FOLDERS = ("sim/sensors", "filters/measurements")
#: the simulator's and the alignment's scenario readers (docs/architecture.md "Conventions");
#: the files of a paper folder ``papers/paperNNN/`` are left out (each folder holds the same)
SHARED_NAMES = {"__init__", "scenario"}


def duplicate_module_names(paths) -> dict:
    """``{name: [folders]}`` of module file names found in more than one folder, leaving out
    the kind names paired by :data:`PAIRED_FOLDERS` and :data:`SHARED_NAMES`."""
    folders = {}
    for p in paths:
        rel = p.relative_to(PKG)
        if rel.parts[0] == "papers" and len(rel.parts) > 2:
            continue  # every paper folder holds the same files (claims.py, filters.py)
        folders.setdefault(rel.stem, []).append(rel.parent.as_posix())
    return {name: sorted(where) for name, where in folders.items()
            if len(where) > 1 and name not in SHARED_NAMES
            and sorted(where) != sorted(PAIRED_FOLDERS)}


def test_module_names_are_unique_but_for_the_sensor_pairs():
    dup = duplicate_module_names(sorted(PKG.rglob("*.py")))
    assert not dup, f"rename so each module name says what it holds: {dup}"


def test_the_name_rule_itself():
    # the check above must be able to fail: a third folder with a kind's name is refused
    paths = [PKG / "sim/sensors/gnss.py", PKG / "filters/measurements/gnss.py",
             PKG / "nav/layout.py", PKG / "filters/layout.py", PKG / "nav/gnss.py"]
    assert duplicate_module_names(paths) == {
        "layout": ["filters", "nav"], "gnss": ["filters/measurements", "nav", "sim/sensors"]}


def test_the_package_docstring_names_every_subpackage():
    import fuzzynav

    subpackages = {p.name for p in PKG.iterdir() if (p / "__init__.py").is_file()}
    listed = {line.strip() for line in fuzzynav.__doc__.splitlines()}
    assert subpackages <= listed, f"add to fuzzynav/__init__.py: {subpackages - listed}"
