"""Calling the compiled filter loop without re-typing its kernel tables on every run.

The loop receives the measurement models and adaptation policies as tuples of compiled
functions.  numba types every argument on every call, and a tuple of compiled functions is
the one argument it cannot type from a fingerprint: it falls back to Python, which inspects
each function's signature and looks up its machine address -- milliseconds per run, the
same answer every time.  :func:`memoise_table_types` keeps that answer per tuple; numba still
types and checks every other argument and picks the overload itself, so a run cannot reach
a kernel compiled for other types.
"""
from __future__ import annotations

from numba.core.dispatcher import Dispatcher

#: tuples of kernels whose numba type is kept (a process builds a handful: one per registry
#: state); past this many the memo is cleared rather than grown
MAX_TABLES = 64


def _is_table(val) -> bool:
    return type(val) is tuple and len(val) > 0 and all(isinstance(v, Dispatcher) for v in val)


def memoise_table_types(dispatcher: Dispatcher) -> Dispatcher:
    """Make ``dispatcher`` type a tuple of compiled functions once per distinct tuple.

    The key is the tuple's functions (by identity) and how many overloads each has, so a
    kernel compiled for a new signature later is typed afresh.  Returns ``dispatcher``.
    """
    plain = dispatcher.typeof_pyval
    memo = {}

    def typeof_pyval(val):
        if not _is_table(val):
            return plain(val)
        key = (tuple(map(id, val)), tuple(len(v.overloads) for v in val))
        hit = memo.get(key)
        if hit is None:
            if len(memo) >= MAX_TABLES:
                memo.clear()
            # the tuple itself is kept with its type: the ids in the key stay its functions'
            hit = memo[key] = (val, plain(val))
        return hit[1]

    # numba's dispatcher looks this method up on the instance for every argument it cannot
    # fingerprint (numba/_dispatcher.cpp), so an instance attribute takes effect
    dispatcher.typeof_pyval = typeof_pyval
    return dispatcher
