"""Patches numba: the compiled filter loop called without re-typing its kernel tables.

This module patches numba internals: an instance ``typeof_pyval`` on the loop's dispatcher
(numba's C dispatcher looks it up per argument) and the module-level lookups
``numba.experimental.function_type._get_wrapper_address`` / ``_get_jit_address``.  Both are
applied only on the numba releases in :data:`CHECKED_NUMBA`, those the tests ran on
(``tests/filters/test_run_overhead.py``, ``tests/filters/test_numba_patch_dispatch.py``);
on any other release -- pyproject's lower bound 0.59 included, which cannot be installed
beside numpy 2.4 to be checked -- numba is left as it is and every run takes numba's own
path, with the same results (the fallback is tested by forcing it).  The measured
gain: ``benchmarks/bench_patches.py`` (``docs/benchmarks.md``, "Library patches").

The loop receives the measurement models and adaptation policies as tuples of compiled
functions.  numba types every argument on every call, and a tuple of compiled functions is
the one argument it cannot type from a fingerprint: it falls back to Python, which inspects
each function's signature and looks up its machine address -- milliseconds per run, the
same answer every time.  :func:`memoise_table_types` keeps that answer per tuple; numba still
types and checks every other argument and picks the overload itself, so a run cannot reach
a kernel compiled for other types.  Unboxing the tuple then asks Python, per function, for
the addresses of its compiled code for the signature the loop was typed with (two lookups
through the overload table per function, ~0.1 ms each); :func:`memoise_kernel_addresses`
keeps those per function and signature.
"""
from __future__ import annotations

import numba
import numpy as np
import numba.experimental.function_type as _function_type
from numba.core.dispatcher import Dispatcher

__all__ = ["CHECKED_NUMBA", "numba_checked", "MAX_TABLES", "memoise_table_types",
           "memoise_kernel_addresses", "restore_kernel_addresses"]

#: numba releases ``(major, minor)`` the patches were checked against, both ends included
#: (widen it after running the tests above on another release)
CHECKED_NUMBA = ((0, 68), (0, 68))


def numba_checked(version: str | None = None) -> bool:
    """Whether numba ``version`` (default: the installed one) is in :data:`CHECKED_NUMBA`."""
    major, minor = (int(p) for p in (version or numba.__version__).split(".")[:2])
    return CHECKED_NUMBA[0] <= (major, minor) <= CHECKED_NUMBA[1]


#: tuples of kernels whose numba type is kept (a process builds a handful: one per registry
#: state); past this many the memo is cleared rather than grown
MAX_TABLES = 64


_INT64 = (-(1 << 63), 1 << 63)


def _type_key(val):
    """What numba's type of ``val`` depends on, as a hashable key, or ``None`` for a value
    this module does not know how numba types (left to numba every time).

    A tuple (a named one by its class) is the key of its items; an array its class, dtype,
    dimensions, layout, whether it is read-only or unaligned (what numba's
    ``typeof`` reads of it); a compiled function its identity and overload count; a Python
    number its class (an int whether it fits int64, numba typing a larger one otherwise).
    """
    if isinstance(val, tuple):
        items = tuple(_type_key(v) for v in val)
        return None if None in items else (type(val), items)
    if isinstance(val, Dispatcher):
        return (Dispatcher, id(val), len(val.overloads))
    if isinstance(val, np.ndarray):
        f = val.flags
        return (type(val), val.dtype.str, val.ndim, f.c_contiguous, f.f_contiguous,
                f.writeable, f.aligned)
    if type(val) is int:
        return (int, _INT64[0] <= val < _INT64[1])
    if type(val) in (float, bool):
        return type(val)
    return None


def memoise_table_types(dispatcher: Dispatcher) -> Dispatcher:
    """Make ``dispatcher`` type a tuple holding compiled functions once per distinct type.

    numba asks :meth:`typeof_pyval` only for an argument it could not fingerprint: a tuple
    of compiled functions (the measurement models, the adaptation policies) or a named
    tuple holding one (the bank, whose share controller holds its weighing kernel).  The
    key is :func:`_type_key` -- the functions by identity and overload count, so a kernel
    compiled for a new signature later is typed afresh -- and the value numba's own answer
    for the first tuple of that key.  Returns ``dispatcher`` (unchanged on a numba release
    outside :data:`CHECKED_NUMBA`).
    """
    if not numba_checked():
        return dispatcher
    plain = dispatcher.typeof_pyval
    memo = {}

    def typeof_pyval(val):
        key = _type_key(val) if isinstance(val, tuple) else None
        if key is None:
            return plain(val)
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


def _memoised_address(lookup):
    """``lookup(func, sig)`` answered once per compiled function and signature object.

    numba's unboxing code passes the signature as a constant it unpickles once, so the same
    object comes back call after call: the key is the pair's identities (both kept alive by
    the entry, so an identity is not reused while its entry lives) and the function's
    overload count, so a function compiled for more signatures since is asked afresh.
    """
    memo = {}

    def address(func, sig):
        if not isinstance(func, Dispatcher):
            return lookup(func, sig)
        key = (id(func), id(sig))
        hit = memo.get(key)
        if hit is not None and hit[2] == len(func.overloads):
            return hit[3]
        addr = lookup(func, sig)
        if len(memo) >= MAX_TABLES * 16:
            memo.clear()
        memo[key] = (func, sig, len(func.overloads), addr)
        return addr

    address.memoised = True
    address.wrapped = lookup
    return address


def memoise_kernel_addresses() -> None:
    """Make numba look up a compiled function's addresses once per signature (idempotent).

    Replaces the two module-level lookups that numba's generated unboxing code fetches by
    name on every call (``numba.experimental.function_type._get_wrapper_address`` and
    ``_get_jit_address``) with memoised ones answering the same.  An address stays valid
    while its function lives: numba never frees an overload's code (``Dispatcher.recompile``
    would, and fuzzynav never calls it).  Nothing is replaced on a numba release outside
    :data:`CHECKED_NUMBA`.
    """
    if not numba_checked():
        return
    for name in ("_get_wrapper_address", "_get_jit_address"):
        lookup = getattr(_function_type, name, None)  # None: another numba, left as it is
        if lookup is not None and not getattr(lookup, "memoised", False):
            setattr(_function_type, name, _memoised_address(lookup))


def restore_kernel_addresses() -> None:
    """Undo :func:`memoise_kernel_addresses` (numba's own lookups again; for measuring)."""
    for name in ("_get_wrapper_address", "_get_jit_address"):
        lookup = getattr(_function_type, name, None)
        if getattr(lookup, "memoised", False):
            setattr(_function_type, name, lookup.wrapped)
