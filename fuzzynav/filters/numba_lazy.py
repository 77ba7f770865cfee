"""Kernels with one fixed signature, compiled when first used rather than at import.

This module patches numba: :class:`OneSignatureDispatcher` subclasses numba's
``CPUDispatcher`` and relies on its private state (``_can_compile``); it is checked against
numba 0.68 (``tests/filters/test_lazy_kernels.py``).  The measured gain: a cold
``fuzzynav run paper000 --filter ekf`` takes 0.42 times the CPU time
(``docs/benchmarks.md``, "Cold start").

The filter loop dispatches measurement models and adaptation policies through numba
first-class functions: a kernel table is a tuple of dispatchers, and numba types it as one
``UniTuple(FunctionType(sig))`` only when every dispatcher has exactly one overload and
compilation disabled -- what ``@njit(sig)`` gives, by compiling at decoration.  With a
cold cache that compiled every registered kernel when the registries loaded (about a
third of a cold ``fuzzynav run``), most of them for sensors and policies the run never
uses.

:func:`njit_signature` gives the same dispatcher state on demand instead: the kernel is
compiled for its one signature (or loaded from numba's cache) and compilation disabled the
first time anything needs it -- a call from Python, a jitted caller being typed, or the
kernel being typed as a first-class function (a kernel table).  Until then it costs
nothing.  The compiled code is the one ``@njit(sig)`` would produce.
"""
from __future__ import annotations

from numba.core.registry import CPUDispatcher

__all__ = ["KERNEL_OPTIONS", "OneSignatureDispatcher", "njit_signature", "table_of"]

#: options of every kernel (those of the modules' ``@nb.njit(SIG, cache=True, ...)``)
KERNEL_OPTIONS = {"nopython": True, "error_model": "numpy"}


class OneSignatureDispatcher(CPUDispatcher):
    """A numba dispatcher compiled for one signature, ``sig``, on first use."""

    def __init__(self, py_func, locals=None, targetoptions=None, sig=None):
        super().__init__(py_func, locals=locals or {}, targetoptions=targetoptions or {})
        self.lazy_sig = sig

    @property
    def is_compiled(self) -> bool:
        """Whether the kernel has been compiled (or loaded from the cache) yet."""
        return not self._can_compile

    def ensure_compiled(self) -> "OneSignatureDispatcher":
        """Compile (or load from the cache) the one signature, then disable compiling."""
        if self._can_compile:
            self.compile(self.lazy_sig)
            self.disable_compile()
        return self

    # numba's entry points that need an overload: each compiles the one signature first
    def _compile_for_args(self, *args, **kws):  # a call from Python with no overload yet
        if self._can_compile:  # numba calls what this returns with the arguments
            return self.ensure_compiled().overloads[tuple(self.lazy_sig.args)].entry_point
        return super()._compile_for_args(*args, **kws)

    def get_call_template(self, args, kws):  # a jitted caller is being typed
        self.ensure_compiled()
        return super().get_call_template(args, kws)

    def get_function_type(self):  # typed as a first-class function (a kernel table)
        self.ensure_compiled()
        return super().get_function_type()

    def get_compile_result(self, sig):  # the address of its code, for a kernel table
        self.ensure_compiled()
        return super().get_compile_result(sig)

    def _reduce_states(self):
        return dict(super()._reduce_states(), lazy_sig=self.lazy_sig)

    @classmethod
    def _rebuild(cls, uuid, py_func, locals, targetoptions, can_compile, sigs, lazy_sig=None):
        self = super()._rebuild(uuid, py_func, locals, targetoptions, can_compile, sigs)
        self.lazy_sig = lazy_sig
        return self


def njit_signature(sig, cache: bool = True):
    """Decorator: like ``numba.njit(sig, cache=cache, error_model="numpy")``, but the
    compilation happens on first use (:class:`OneSignatureDispatcher`)."""

    def wrap(py_func):
        disp = OneSignatureDispatcher(py_func, targetoptions=dict(KERNEL_OPTIONS), sig=sig)
        if cache:
            disp.enable_caching()
        return disp

    return wrap


def table_of(kernels, used, stand_in) -> tuple:
    """The kernel table ``kernels`` with every entry not in ``used`` (indices; None: all
    used) replaced by ``stand_in``, a kernel of the same signature that the run never
    calls, so that only the used kernels are compiled."""
    if used is None:
        return tuple(kernels)
    used = {int(i) for i in used}
    return tuple(k if i in used else stand_in for i, k in enumerate(kernels))
