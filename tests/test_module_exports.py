"""Every module says what it exports: an ``__all__`` naming only what the module defines
or imports (checked on the source; issue 23 §8 found it in 5 of 192 modules)."""
import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "fuzzynav"
MODULES = sorted(p for p in PKG.rglob("*.py") if p.name not in ("__init__.py", "__main__.py"))


def _bound_names(tree) -> set:
    """Names a module binds at its top level (defs, classes, assignments, imports), also
    inside top-level ``if``/``try`` blocks."""
    names = set()
    body = list(tree.body)
    while body:
        node = body.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                names |= {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
        elif isinstance(node, (ast.If, ast.Try)):
            body += node.body + getattr(node, "orelse", []) + getattr(node, "finalbody", [])
            for h in getattr(node, "handlers", []):
                body += h.body
    return names


def _all_of(tree):
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__"
                                                for t in node.targets):
            return [ast.literal_eval(e) for e in node.value.elts]
    return None


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PKG)))
def test_a_module_lists_what_it_exports(path):
    tree = ast.parse(path.read_text())
    public = {n for n in _bound_names(tree) if not n.startswith("_")}
    exported = _all_of(tree)
    defined = {n.name for n in tree.body
               if isinstance(n, (ast.FunctionDef, ast.ClassDef)) and not n.name.startswith("_")}
    if exported is None:
        assert not defined, f"{path.name} defines {sorted(defined)} but has no __all__"
        return
    assert len(exported) == len(set(exported)), f"a name twice in {path.name}'s __all__"
    stale = set(exported) - public - {"__version__"}
    assert not stale, f"{path.name}: __all__ names {sorted(stale)}, which it does not bind"
