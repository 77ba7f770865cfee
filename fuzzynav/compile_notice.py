"""One line on stderr when a command starts compiling numba kernels.

A run on a cold kernel cache (a new version of the package, a fresh machine) spends most of
its time compiling; without a word it looks hung, and a progress bar says nothing when the
output goes to a file or a CI log.  :func:`install` registers a listener on numba's
``"numba:compile"`` event: the first compilation of the process (a kernel not in the cache)
prints :func:`notice_text` to stderr once, terminal or not; a warm run compiles nothing and
prints nothing.  Whether the cache is cold -- the keyed directory of
:func:`fuzzynav._key_numba_cache` missing or without a compiled kernel -- is decided here
only (:func:`cache_is_cold`), so the estimate in the line fits the case.
"""
from __future__ import annotations

import os
import sys
import threading
from pathlib import Path

__all__ = ["COLD_RUN_S", "COLD_TEXT", "PARTIAL_TEXT", "kernel_cache", "compiled_count",
           "cache_is_cold", "notice_text", "CompileNotice", "install", "announce"]

#: a cold ``fuzzynav run paper000 --filter ekf`` [s] on a 2-core machine (docs/benchmarks.md)
COLD_RUN_S = 30

#: the line when the keyed cache is empty
COLD_TEXT = f"compiling numba kernels (first run, ~{COLD_RUN_S} s) …"
#: the line when some kernels are cached but this command needs others
PARTIAL_TEXT = "compiling numba kernels (not in the cache yet, a few seconds each) …"


def kernel_cache():
    """numba's cache directory keyed to this package's sources, or None when not keyed
    (``FUZZYNAV_NUMBA_CACHE=0`` leaves numba's own per-file caches)."""
    import numba

    if os.environ.get("FUZZYNAV_NUMBA_CACHE", "1") == "0" or not numba.config.CACHE_DIR:
        return None
    return Path(numba.config.CACHE_DIR)


def compiled_count(cache) -> int:
    """Compiled kernels in the cache directory ``cache`` (one index file each)."""
    return sum(1 for _ in cache.rglob("*.nbi")) if cache is not None and cache.is_dir() else 0


def cache_is_cold(cache=None) -> bool:
    """Whether the keyed kernel cache (``cache``, default :func:`kernel_cache`) holds no
    compiled kernel: the next run compiles everything it uses."""
    cache = kernel_cache() if cache is None else cache
    return cache is not None and compiled_count(cache) == 0


def notice_text(cold: bool) -> str:
    """The line printed: :data:`COLD_TEXT` on a cold cache, else :data:`PARTIAL_TEXT`."""
    return COLD_TEXT if cold else PARTIAL_TEXT


class CompileNotice:
    """Writes one line to ``stream`` (default: ``sys.stderr`` when it is written) before
    the first compilation it hears of, and nothing after (see :meth:`announce`)."""

    def __init__(self, stream=None, cold=None):
        self._stream = stream
        self._cold = cold  # None: decided at the first compilation
        self._lock = threading.Lock()
        self.said = False

    def announce(self) -> bool:
        """Print the line unless it was printed; returns whether this call printed it."""
        with self._lock:
            if self.said:
                return False
            self.said = True
        cold = cache_is_cold() if self._cold is None else self._cold
        stream = self._stream if self._stream is not None else sys.stderr
        try:
            print(notice_text(cold), file=stream, flush=True)
        except (OSError, ValueError):  # a closed stderr must not fail the compilation
            pass
        return True


def _listener(notice: CompileNotice):
    from numba.core import event

    class _OnCompile(event.Listener):
        def on_start(self, ev):
            notice.announce()

        def on_end(self, ev):
            pass

    return _OnCompile()


#: the process's notice (:func:`install`), None until installed
_INSTALLED = None


def install(stream=None) -> CompileNotice:
    """Make the first numba compilation of this process print the line (idempotent:
    the notice of the first call is returned again)."""
    global _INSTALLED
    if _INSTALLED is None:
        from numba.core import event

        _INSTALLED = CompileNotice(stream)
        event.register("numba:compile", _listener(_INSTALLED))
    return _INSTALLED


def announce() -> bool:
    """Print the line now if :func:`install` was called and it was not printed yet (for a
    command that knows it is about to compile, before numba says so)."""
    return _INSTALLED.announce() if _INSTALLED is not None else False
