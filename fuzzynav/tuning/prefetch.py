"""The baseline's runs of a study's start-up, shared among as many processes as it has workers.

Before a study forks its workers, the parent loads every training log and runs the baseline
filter on each (:func:`fuzzynav.tuning.run.warm_evaluator`), so that the workers start with
everything a trial needs.  Done serially, that start-up is about a second -- 7 % of a
60-trial study with two workers, during which the second CPU idles.  :func:`prepare_shared`
forks helper processes once the kernels are loaded (they load none): each runs the baseline
on its share of the runs and sends the metrics back, pickled -- bit for bit what the parent
would have computed, by the same code on the same data.  The parent meanwhile runs its own,
smaller share and loads the helpers' logs, which the workers forked after it need.
"""
from __future__ import annotations

import multiprocessing


def split(runs: list, processes: int) -> tuple:
    """``(the parent's share, [each helper's share])`` of ``runs`` among ``processes``.

    The parent also loads the helpers' logs (about half the time of a baseline run with
    its log): it takes one share in ``processes + 1``, the helpers the rest, in turn.
    """
    n_own = round(len(runs) / (processes + 1))
    rest = runs[n_own:]
    return runs[:n_own], [rest[i::processes - 1] for i in range(processes - 1)]


def _send_baselines(evaluator, share, conn) -> None:
    """A helper's body: the baseline's metrics on ``share``, sent through ``conn``."""
    try:
        conn.send({run: evaluator.baseline(*run) for run in share})
    except Exception:  # noqa: BLE001 -- the parent computes (and reports) what is missing
        pass
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
    runs shared with ``processes - 1`` forked helpers (only where workers are forked too:
    the caller passes 1 elsewhere).  Returns ``evaluator``.

    Call it after the kernels are loaded (:func:`fuzzynav.tuning.warmup.compile_by_running`):
    a helper forked before would load them again.  A helper that fails delivers nothing;
    what is missing is computed here, and its error raised here, as without helpers.
    """
    todo = evaluator.pending(runs)
    if processes < 2 or len(todo) < 2:
        return evaluator.prepare(runs)
    own, shares = split(todo, min(processes, len(todo)))
    helpers = [Helper(evaluator, share) for share in shares if share]
    evaluator.prepare(own)
    for run in todo:  # the helpers' logs, which the workers inherit
        evaluator.log(*run)
    known = {}
    for helper in helpers:
        known.update(helper.collect())
    return evaluator.prepare(runs, known)
