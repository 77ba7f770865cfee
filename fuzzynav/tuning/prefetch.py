"""A study's start-up done by as many processes as it has workers.

Before a study forks its workers, the parent loads the kernels, every training log and the
baseline filter's metrics on each, so that the workers start with everything a trial needs.
Done serially, that start-up is over a second -- 7 % of a 60-trial study with two workers,
during which the second CPU idles.  With several processes (:func:`warm_shared`):

* the logs load in a thread while the kernels load (reading and checksumming a log's file
  releases the GIL; loading kernels mostly holds it);
* then helper processes are forked (the kernels and logs loaded: they load none) and each
  runs the baseline on its share of the runs and sends the metrics back, pickled -- bit
  for bit what the parent would have computed, by the same code on the same data -- while
  the parent runs its own share.
"""
from __future__ import annotations

import multiprocessing
import threading

__all__ = ["split", "Helper", "prepare_shared", "warm_shared"]


def split(runs: list, processes: int) -> tuple:
    """``(the parent's share, [each helper's share])`` of ``runs``, dealt in turn."""
    return runs[::processes], [runs[i::processes] for i in range(1, processes)]


def _send_baselines(evaluator, share, conn) -> None:
    """A helper's body: the baseline's metrics on ``share``, sent through ``conn``."""
    try:
        conn.send({run: evaluator.baseline(*run) for run in share})
    except BaseException:  # noqa: BLE001 -- the parent computes (and reports) what is
        pass  # missing; on Ctrl-C (sent to the helper too) it stops itself, no traceback here
    finally:
        conn.close()


class Helper:
    """A process forked from this one that runs the baseline on a share of the runs."""

    def __init__(self, evaluator, share):
        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=_send_baselines, args=(evaluator, share, child),
                                 daemon=True)  # (daemon: never outlives the parent)
        self._proc.start()
        child.close()  # the helper's end: EOF here when it exits without sending

    def collect(self) -> dict:
        """The metrics it computed ((scenario, seed) -> metrics; empty if it failed)."""
        try:
            known = self._conn.recv()
        except (EOFError, OSError):
            known = {}
        finally:
            self._conn.close()
        self._proc.join()
        return known


def prepare_shared(evaluator, runs, processes: int = 1):
    """Load the logs of ``runs`` into ``evaluator`` and run the baseline on each, those
    runs shared with ``processes - 1`` forked helpers.  Returns ``evaluator``.

    Call it with the kernels loaded (a helper forked before would load them again) and no
    other thread running (a fork copies only this one).  A helper that fails delivers
    nothing: what is missing is computed here, and its error raised here, as without
    helpers.
    """
    todo = evaluator.pending(runs)
    if processes < 2 or len(todo) < 2:
        return evaluator.prepare(runs)
    for run in todo:  # (loaded already by warm_shared's thread, unless it failed)
        evaluator.log(*run)
    own, shares = split(todo, min(processes, len(todo)))
    helpers = [Helper(evaluator, share) for share in shares]
    evaluator.prepare(own)
    known = {}
    for helper in helpers:
        known.update(helper.collect())
    return evaluator.prepare(runs, known)


def _load_logs(evaluator, runs, stop) -> None:
    try:
        for run in runs:
            if stop.is_set():  # the start-up failed or was interrupted
                return
            evaluator.log(*run)
    except Exception:  # noqa: BLE001 -- loaded again (and the error raised) by the caller
        pass


def warm_shared(cfg, cache_dir=None, processes: int = 1):
    """A warm :class:`~fuzzynav.tuning.objective.Evaluator` of ``cfg``'s training runs (every
    training log loaded, simulated into the cache if missing so that workers never race to
    create it; the baseline's metrics on each; the kernels of a candidate's run loaded),
    made by ``processes`` processes: the kernels loaded with the logs loading alongside (a
    thread), then the baseline runs shared (:func:`prepare_shared`).  Pass 1 where workers
    are not forked."""
    from fuzzynav.tuning.objective import Evaluator
    from fuzzynav.tuning.warmup import compile_by_running

    evaluator = Evaluator(cfg, cache_dir)
    loader, stop = None, threading.Event()
    if processes > 1:
        loader = threading.Thread(target=_load_logs, args=(evaluator, cfg.train[1:], stop),
                                  daemon=True)
        loader.start()
    try:
        compile_by_running(cfg, cache_dir, evaluator)  # loads the kernels on train[0]
    except BaseException:  # an error or Ctrl-C: the loader stops after the log it is on
        stop.set()
        raise
    finally:
        if loader is not None:
            loader.join()  # before any fork
    return prepare_shared(evaluator, cfg.train, processes)
