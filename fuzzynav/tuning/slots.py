"""The trial-slot lock: "count the study's trials, then start one" as one step.

Workers stop when finished + running trials reach the total; without a lock two workers
can both count one short of it and both start a trial.  The lock is held from the count
until the new trial is ``RUNNING`` (so the next worker counts it):

* journal file: an advisory ``flock`` on the journal itself (Optuna's own journal lock
  is a separate symlink file, so they never interfere; nothing is left behind, and the
  kernel drops the lock of a killed process);
* PostgreSQL: a session-level advisory lock keyed by the study name, on a connection of
  its own (the server drops it when the worker's connection goes);
* other storages: no lock (a worker more than the total may start near the end).
"""
from __future__ import annotations

import zlib

__all__ = ["TrialSlots"]


class TrialSlots:
    """Exclusive "count, then start a trial" among the workers of one study.

    Parameters
    ----------
    url : str
        The storage URL (``journal:PATH``, ``postgresql://...``, ...).
    study_name : str
        Keys the PostgreSQL advisory lock (one lock per study).
    """

    def __init__(self, url: str, study_name: str):
        self._path = url[len("journal:"):] if url.startswith("journal:") else None
        self._fh = None
        self._conn = None
        self._held = False
        if url.startswith(("postgresql:", "postgresql+", "postgres:")):
            import sqlalchemy

            engine = sqlalchemy.create_engine(url, poolclass=sqlalchemy.pool.NullPool)
            self._conn = engine.connect().execution_options(isolation_level="AUTOCOMMIT")
            self._key = zlib.crc32(f"fuzzynav-study:{study_name}".encode())

    def _sql(self, query: str) -> None:
        import sqlalchemy

        self._conn.execute(sqlalchemy.text(query), {"k": self._key})

    @property
    def exclusive(self) -> bool:
        """Whether this worker holds a real lock (a journal file or PostgreSQL storage; other
        storages have none and every worker counts on its own)."""
        return self._held and (self._fh is not None or self._conn is not None)

    def acquire(self) -> None:
        """Block until this worker holds the lock (no-op if it already does)."""
        if self._held:
            return
        if self._path is not None:
            import fcntl

            self._fh = open(self._path, "ab")
            fcntl.flock(self._fh, fcntl.LOCK_EX)
        elif self._conn is not None:
            self._sql("SELECT pg_advisory_lock(:k)")
        self._held = True

    def release(self) -> None:
        """Let the next worker count (no-op if not held)."""
        if not self._held:
            return
        if self._fh is not None:
            import fcntl

            fcntl.flock(self._fh, fcntl.LOCK_UN)
            self._fh.close()
            self._fh = None
        elif self._conn is not None:
            self._sql("SELECT pg_advisory_unlock(:k)")
        self._held = False

    def close(self) -> None:
        """Release and drop the database connection."""
        self.release()
        if self._conn is not None:
            self._conn.close()
            self._conn = None
