"""Compile the loop's heavy callees in a second process while this one compiles the rest.

A cold ``fuzzynav run`` spends most of its time compiling, one kernel after the other, on
one core: numba holds a process-wide lock while it compiles.  The covariance kernels of
the filter loop and a few other callees (:data:`KERNELS`; with their 15-state copies about
a third of a cold run's compile time) do not depend on the rest, and the loop calls them
with one signature each (its own C-contiguous work arrays, :func:`signatures`).  So when
the loop is about to be compiled and they are neither compiled nor in the kernel cache,
:func:`start` launches ``python -m fuzzynav.filters.precompile``: it compiles them into
the same keyed cache (numba writes each entry to a temporary file and renames it), from
the last the loop needs to the first, writing ``start NAME`` and ``done NAME``; this
process compiles the measurement models and the loop's callees from the first on.  When
its typing reaches one of the kernels (:class:`_WaitingCache`, :meth:`Helper.claim`): done
-- loaded from the cache, the code this process would have compiled (a warm run loads
every kernel so); being compiled -- it waits (at most :data:`WAIT_S`); not started -- it
compiles the kernel itself and tells the helper to skip it.  Results never depend on
which process compiled (the same code; ``tools/behaviour_lock.py``).

Off with ``FUZZYNAV_PRECOMPILE=0``, on one CPU, and without the keyed cache
(``FUZZYNAV_NUMBA_CACHE=0``).  The hook goes through the dispatcher's private cache object
(``_cache``, numba 0.68) and the cache's index path (``tests/filters/test_precompile.py``).
"""
from __future__ import annotations

import atexit
import importlib
import os
import select
import subprocess
import sys
import time

__all__ = ["KERNELS", "WAIT_S", "ENV_SWITCH", "ENV_CACHE", "signatures", "dispatcher", "needed",
           "Helper", "enabled", "start"]

#: the kernels the helper may compile (under ``fuzzynav.``), in the reverse of the order in
#: which the loop's typing reaches them: this process works from the front, the helper from
#: the back, and they meet in the middle (:meth:`Helper.claim`)
KERNELS = ("filters.feedback.feedback", "filters.kalman.covariance_ok", "filters.kalman.correct",
           "filters.kalman.scale_predicted", "filters.loop._innovation",
           "filters.kalman.innovation_cov", "filters.kalman.propagate_tail",
           "filters.error_model.discretize_tail", "filters.error_model.fill_F",
           "nav.strapdown.mech_step")
#: how long [s] this process waits for the kernel the helper is compiling before
#: compiling it itself
WAIT_S = 120.0
#: the environment variable that turns the helper off ("0")
ENV_SWITCH = "FUZZYNAV_PRECOMPILE"
#: set in the helper's environment: the cache directory it must compile into
ENV_CACHE = "FUZZYNAV_PRECOMPILE_CACHE"


def signatures() -> dict:
    """Kernel name -> the argument types the filter loop calls it with (its own
    C-contiguous float64 / int64 work arrays, int64 counts, float64 times)."""
    from numba import types as t

    v, M, iv, i, f = t.float64[::1], t.float64[:, ::1], t.int64[::1], t.int64, t.float64
    return {"filters.feedback.feedback": (v, v, v, v),
            "filters.kalman.covariance_ok": (M,),
            "filters.kalman.correct": (M, M, M, v, i, v, M, M, v, M, M, v),
            "filters.kalman.scale_predicted": (M, M, f, M, i, v),
            "filters.loop._innovation": (M, v, i, M, M, v, v, M, M, v, i),
            "filters.kalman.innovation_cov": (M, M, i, M, M),
            "filters.kalman.propagate_tail": (M, M, M, M, i),
            "filters.error_model.discretize_tail": (M, v, f, M, M, M, i),
            "filters.error_model.fill_F": (M, v, M, v, iv, iv, v),
            "nav.strapdown.mech_step": (v, v, v, v, f, v, M)}


def dispatcher(name):
    """The numba dispatcher of kernel ``name`` (``"filters.kalman.correct"``)."""
    module, func = name.rsplit(".", 1)
    return getattr(importlib.import_module(f"fuzzynav.{module}"), func)


def _index_path(disp):
    """The kernel's index file in numba's cache, or None when numba's layout differs."""
    path = getattr(getattr(getattr(disp, "_cache", None), "_cache_file", None),
                   "_index_path", None)
    return path if isinstance(path, str) else None


def needed() -> list:
    """The kernels neither compiled in this process nor in the kernel cache."""
    out = []
    for name in KERNELS:
        disp = dispatcher(name)
        path = _index_path(disp)
        if not disp.overloads and path is not None and not os.path.exists(path):
            out.append(name)
    return out


class Helper:
    """The helper process and what it reported: a line ``start NAME`` before it compiles a
    kernel, ``done NAME`` when the kernel is in the cache; this process writes ``skip NAME``
    for a kernel it compiles itself (:meth:`claim`)."""

    def __init__(self, proc):
        self.proc = proc
        self.started, self.done = set(), set()
        self._buf = b""
        #: seconds this process spent waiting for the helper; the helper's CPU seconds
        #: (known once it ended: :meth:`stop`)
        self.waited_s = 0.0
        self.cpu_s = None

    def _read(self, timeout_s) -> bool:
        """Take in what the helper wrote within ``timeout_s``; False once it has ended."""
        fd = self.proc.stdout.fileno()
        if not select.select([fd], [], [], max(timeout_s, 0.0))[0]:
            return True
        chunk = os.read(fd, 4096)
        if not chunk:
            return False
        self._buf += chunk
        *lines, self._buf = self._buf.split(b"\n")
        for line in lines:
            what, _, name = line.decode().partition(" ")
            (self.started if what == "start" else self.done).add(name)
        return True

    def claim(self, name) -> bool:
        """Whether ``name`` is (now) in the cache from the helper: True if it is done or
        was being compiled and got done within :data:`WAIT_S`; False if the helper had not
        started it (then it is told to skip it: this process compiles it), has ended or
        is too slow."""
        t0 = time.monotonic()
        try:
            alive = self._read(0.0)
            if name not in self.started:
                self._skip(name)
                return False
            while alive and name not in self.done and time.monotonic() - t0 < WAIT_S:
                alive = self._read(WAIT_S - (time.monotonic() - t0))
            return name in self.done
        finally:
            self.waited_s += time.monotonic() - t0

    def _skip(self, name):
        try:
            self.proc.stdin.write(f"skip {name}\n".encode())
            self.proc.stdin.flush()
        except (BrokenPipeError, ValueError):  # the helper has ended
            pass

    def stop(self):
        """End the helper (killed if it still runs) and note its CPU seconds."""
        if self.proc.returncode is not None:
            return
        self.proc.kill()  # nothing happens to a helper that has ended (not yet reaped)
        try:
            _, status, usage = os.wait4(self.proc.pid, 0)
        except ChildProcessError:
            status, usage = 0, None
        self.proc.returncode = os.waitstatus_to_exitcode(status)
        if usage is not None:
            self.cpu_s = usage.ru_utime + usage.ru_stime
        for pipe in (self.proc.stdin, self.proc.stdout):
            try:
                pipe.close()
            except OSError:
                pass


class _WaitingCache:
    """Stands in for a dispatcher's cache until its first load: waits for the helper,
    then puts the dispatcher's own cache back and loads from it."""

    def __init__(self, disp, name, helper):
        self._disp, self._name, self._helper = disp, name, helper
        self._own = disp._cache

    def load_overload(self, sig, target_context):
        self._disp._cache = self._own
        self._helper.claim(self._name)  # a miss below: this process compiles it
        return self._own.load_overload(sig, target_context)

    def __getattr__(self, attr):
        return getattr(self._own, attr)


#: the helper of this process (None: not started) and whether :func:`start` has looked
_HELPER = None
_LOOKED = False


def enabled() -> bool:
    """Whether :func:`start` may launch the helper here."""
    from fuzzynav import compile_notice

    return (os.environ.get(ENV_SWITCH, "1") != "0" and ENV_CACHE not in os.environ
            and len(os.sched_getaffinity(0)) >= 2 and compile_notice.kernel_cache() is not None)


def start():
    """Launch the helper for the kernels not yet compiled or cached (once per process);
    returns it, or None when it is off or nothing is missing."""
    global _HELPER, _LOOKED
    if _LOOKED:
        return _HELPER
    _LOOKED = True
    names = needed() if enabled() else []
    if not names:
        return None
    import numba

    import fuzzynav

    root = os.path.dirname(os.path.dirname(os.path.abspath(fuzzynav.__file__)))
    env = dict(os.environ, **{ENV_CACHE: str(numba.config.CACHE_DIR)})
    env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in [env.get("PYTHONPATH")] if p])
    proc = subprocess.Popen([sys.executable, "-m", __name__, *names], env=env,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL)
    _HELPER = Helper(proc)
    atexit.register(_HELPER.stop)
    for name in names:
        disp = dispatcher(name)
        disp._cache = _WaitingCache(disp, name, _HELPER)
    return _HELPER


def _skipped(fd, skipped: set) -> set:
    """Add the kernels the parent said it compiles itself (``skip NAME`` lines on ``fd``)."""
    while select.select([fd], [], [], 0.0)[0]:
        chunk = os.read(fd, 4096)
        if not chunk:  # the parent has closed the pipe: it needs nothing more
            skipped.add(None)
            break
        skipped.update(line.partition(" ")[2] for line in chunk.decode().splitlines())
    return skipped


def _main(names) -> int:
    """The helper: compile ``names`` in order into the cache directory the parent named,
    skipping those the parent compiles itself."""
    import numba

    import fuzzynav  # noqa: F401  (keys numba's cache directory)

    if str(numba.config.CACHE_DIR) != os.environ.get(ENV_CACHE):
        return 1  # another cache than the parent's: compiling would not help it
    sigs, skipped = signatures(), set()
    for name in names:
        if name in _skipped(0, skipped) or None in skipped:
            continue
        print("start", name, flush=True)
        dispatcher(name).compile(sigs[name])
        print("done", name, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
