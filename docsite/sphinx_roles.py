"""A griffe extension (mkdocs.yml): the docstrings' Sphinx roles as links on the site.

The docstrings name other objects with Sphinx roles (``:func:`propagate```,
``:class:`~fuzzynav.errors.FisError```), which Markdown would show as they are.  Each role
becomes a cross-reference to the object's section of the API reference when the name
resolves, from the docstring's own scope as Python would resolve it, to a public, documented
object of the package; otherwise (numpy, Optuna, a private helper) a code span.  A role
that names a ``fuzzynav.`` path that does not exist is a stale reference: it is logged as a
warning, which fails the strict build.
"""
from __future__ import annotations

import re

import griffe

_ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|obj|exc|const):`([^`]+)`")
_TITLED = re.compile(r"(.*?)\s*<([^>]+)>$")


def _lookup(pkg: griffe.Module, path: str) -> griffe.Object | None:
    """The object of the package at ``path`` (aliases followed), or None."""
    parts = path.split(".")
    if parts[0] != pkg.name:
        return None
    obj = pkg
    try:
        for part in parts[1:]:
            obj = obj.members[part]
            if obj.is_alias:
                obj = obj.final_target
    except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None
    return obj


def _rendered(obj: griffe.Object) -> bool:
    """Whether the API reference has a section for ``obj`` (public and documented)."""
    names = obj.path.split(".")[1:]
    return not any(n.startswith("_") for n in names) and (obj.is_module or bool(obj.docstring))


def _suffix_index(pkg: griffe.Module) -> dict[str, list[griffe.Object]]:
    """Every object of the package under each dotted tail of its path (``b.c``, ``c``)."""
    index: dict[str, list[griffe.Object]] = {}
    stack = [pkg]
    while stack:
        obj = stack.pop()
        parts = obj.path.split(".")
        for i in range(1, len(parts)):
            index.setdefault(".".join(parts[i:]), []).append(obj)
        stack.extend(m for m in obj.members.values() if not m.is_alias)
    return index


def _target(scope: griffe.Object, pkg: griffe.Module, name: str,
            index: dict[str, list[griffe.Object]]) -> griffe.Object | None:
    """Resolve ``name`` (maybe dotted) as written in a docstring of ``scope``: from its
    scope as Python would, else (as Sphinx's search does) the one object whose path ends
    with it."""
    head, _, rest = name.partition(".")
    try:
        path = scope.resolve(head)
    except (griffe.NameResolutionError, AttributeError, KeyError):
        path = head
    obj = _lookup(pkg, f"{path}.{rest}" if rest else path)
    if obj is None and len(index.get(name, ())) == 1:
        obj = index[name][0]
    return obj


def rewrite(text: str, scope: griffe.Object, pkg: griffe.Module,
            index: dict[str, list[griffe.Object]] | None = None) -> str:
    """``text`` with its Sphinx roles as cross-references or code spans.

    Parameters
    ----------
    text : str
        A docstring.
    scope : griffe.Object
        The object the docstring belongs to (names resolve from there).
    pkg : griffe.Module
        The loaded package.
    index : dict, optional
        :func:`_suffix_index` of ``pkg`` (built when not given).

    Returns
    -------
    str
        The docstring with ``[`title`][path]`` for every role whose object is on the site
        and a ``title`` code span for the others.
    """
    index = _suffix_index(pkg) if index is None else index

    def one(match: re.Match) -> str:
        content = " ".join(match.group(1).split())  # a role may be wrapped over lines
        titled = _TITLED.match(content)
        title, name = titled.groups() if titled else (None, content)
        name = name.replace(" ", "")
        short = name.startswith("~")
        name = name.lstrip("~.").removesuffix("()")
        if title is None:
            title = name.rsplit(".", 1)[-1] if short else name
        obj = _target(scope, pkg, name, index)
        if obj is not None and _rendered(obj):
            return f"[`{title}`][{obj.path}]"
        if obj is None and name.startswith(pkg.name + "."):
            where = scope.relative_filepath if hasattr(scope, "relative_filepath") else scope.path
            griffe.logger.warning(  # mkdocstrings passes it to mkdocs: --strict counts it
                "%s: %s: %s names no object of the package (stale reference)",
                where, scope.path, match.group(0))
        return f"`{title}`"

    return _ROLE.sub(one, text)


class SphinxRoles(griffe.Extension):
    """Rewrite the Sphinx roles of every docstring of the package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs) -> None:  # noqa: D102
        index = _suffix_index(pkg)
        stack = [pkg]
        while stack:
            obj = stack.pop()
            if obj.docstring is not None and ":" in obj.docstring.value:
                obj.docstring.value = rewrite(obj.docstring.value, obj, pkg, index)
            stack.extend(m for m in obj.members.values() if not m.is_alias)
