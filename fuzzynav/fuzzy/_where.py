"""Errors of the fuzzy engine and the JSON-path bookkeeping behind their messages.

Definitions validate themselves with paths relative to themselves (``params``,
``terms[1].params``); whoever builds them from a document wraps the construction in
:func:`located` so that the final message carries the full path
(``$.inputs[0].terms[1].params``) and, when loading a file, the file name.
"""
from __future__ import annotations

from contextlib import contextmanager

from fuzzynav.errors import FuzzynavError, InputFileError

__all__ = ["FisError", "FisEvaluationError", "FisCompileError", "join", "fail", "located", "unique"]


class FisError(InputFileError):
    """A fuzzy system (rule file or in-memory definition) is malformed."""


class FisEvaluationError(FuzzynavError, ValueError):
    """``FuzzySystem.evaluate`` was called with inputs that do not fit the system."""


class FisCompileError(FuzzynavError, ValueError):
    """The system cannot be put in the compiled (numba) array form."""


def join(prefix: str, where: str) -> str:
    """Join two JSON-path fragments (``$`` + ``inputs[0]`` -> ``$.inputs[0]``)."""
    if not prefix:
        return where
    if not where:
        return prefix
    if where.startswith("["):
        return prefix + where
    return f"{prefix}.{where}"


def fail(where: str, what: str):
    """Raise a :class:`FisError` for the in-memory document (no file yet)."""
    raise FisError(None, where, what)


@contextmanager
def located(prefix: str, path=None):
    """Prefix the JSON path of any :class:`FisError` raised inside, and set the file.

    Parameters
    ----------
    prefix : str
        Path of the enclosing object, e.g. ``"$.inputs[0]"``.
    path : str or os.PathLike, optional
        File the document came from (kept if an inner error already names one).
    """
    try:
        yield
    except FisError as exc:
        file = exc.path if exc.path is not None else path
        raise FisError(file, join(prefix, exc.where), exc.what) from None


def unique(names, where: str, what: str):
    """Fail on the first repeated name (``where[i].name``)."""
    seen = set()
    for i, n in enumerate(names):
        if n in seen:
            fail(f"{where}[{i}].name", f"duplicate {what} name {n!r}")
        seen.add(n)
