"""Compile the kernels a trial needs once, in the parent, before the workers start.

On a machine where numba's cache for this version of the package is empty, the first trial
compiles every kernel of the filter loop (about a minute and a half on two cores), during which a study
would sit at "0/60 trials".  :func:`warm_up` does that work first, under a message that says
so with a live count of the kernels compiled and the time spent; the workers then load the
kernels from the cache.  With a warm cache it does nothing.
"""
from __future__ import annotations

import sys
import threading
from contextlib import contextmanager

from tqdm.auto import tqdm

from fuzzynav import compile_notice

__all__ = ["MESSAGE", "compile_by_running", "compiling", "warm_up"]

#: the live count's label (on a terminal; the one-line notice is
#: :mod:`fuzzynav.compile_notice`'s, printed whether stderr is a terminal or not)
MESSAGE = "numba kernels compiled"


def compile_by_running(cfg, cache_dir=None, evaluator=None):
    """Run one candidate (the templates' own rules) and the baseline on the first training
    run: the code path of every trial, so every kernel a trial needs gets compiled (or
    loaded from the cache).  Returns the :class:`~fuzzynav.tuning.objective.Evaluator`
    used (``evaluator``, or a new one), its log and baseline of that run kept."""
    from fuzzynav.fuzzy import load_fis
    from fuzzynav.tuning.objective import Evaluator

    systems = {c.name: load_fis(c.template) for c in cfg.controllers}
    ev = evaluator if evaluator is not None else Evaluator(cfg, cache_dir)
    ev.score_systems(systems, *cfg.train[0])
    return ev


@contextmanager
def compiling(progress: bool = True):
    """Say that kernels are being compiled (:func:`fuzzynav.compile_notice.announce`, and a
    live count on a terminal) while the body runs -- if the kernel cache is cold when it
    starts; yields whether it is.

    Enter it before anything imports the filters: importing them (loading a study config
    does) already compiles the kernels that have explicit signatures.
    """
    cache = compile_notice.kernel_cache()
    if not compile_notice.cache_is_cold(cache):
        yield False
        return
    compile_notice.announce()  # the one line, before loading the config compiles
    bar = tqdm(desc=MESSAGE, total=None, unit=" kernels",
               disable=not (progress and sys.stderr.isatty()),
               bar_format="{desc}: {n}, {elapsed}")
    done = threading.Event()

    def count():
        while not done.wait(1.0):
            bar.update(compile_notice.compiled_count(cache) - bar.n)

    watcher = threading.Thread(target=count, daemon=True)
    watcher.start()
    try:
        yield True
    finally:
        done.set()
        watcher.join()
        bar.update(compile_notice.compiled_count(cache) - bar.n)
        bar.close()


def warm_up(cfg, cache_dir=None, progress: bool = True) -> bool:
    """Compile the kernels of ``cfg``'s trials here when the cache is cold (see
    :func:`compiling`); returns whether it was."""
    with compiling(progress) as cold:
        if cold:
            compile_by_running(cfg, cache_dir)
    return cold
