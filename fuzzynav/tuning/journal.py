"""Opening a journal storage file, repairing a record cut off while it was written.

Optuna's journal is one JSON record per line, appended under a lock.  A write interrupted by
a full disk (or a killed process) leaves a partial last line; Optuna skips it while it is the
last line, but the next record is appended right after it, and from then on the journal
raises a decode error on every open: the study is unreadable for good.

:func:`open_journal` checks the tail before every open (and the whole file when Optuna
refuses it).  A damaged file is repaired under Optuna's own journal lock (so no record being
written right now is mistaken for a cut one): every complete record is kept -- also one
appended onto a partial line -- and the partial ones are dropped; the original is kept as
``<journal>.bak`` and one warning line names the file and what was dropped.

Records are forced to disk (``fsync``) only when they change a trial's state or create
something (:class:`SyncOnStateBackend`): a trial's parameters, reports and attributes --
dozens of records per trial, each of which Optuna would ``fsync`` -- reach the disk with the
record that ends the trial.  A killed process loses nothing either way (its writes are in
the kernel already); a power cut may lose the records of the trials still running, which
are retried as any trial of a dead worker.
"""
from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path

from optuna.storages.journal import JournalFileBackend

from fuzzynav.errors import FuzzynavError, OutputError
from fuzzynav.fileio import write_atomic

__all__ = ["RECORD_START", "LAZY_OPS", "tail_ok", "salvage", "repair", "SyncOnStateBackend",
           "open_journal"]

#: how every Optuna journal record starts (where a record appended to a cut one begins)
RECORD_START = b'{"op_code":'
#: bytes read from the end of the file for the quick check of its last record
_TAIL_BYTES = 1 << 16
#: journal operations written without fsync (Optuna's ``JournalOperation`` codes:
#: SET_TRIAL_PARAM, SET_TRIAL_INTERMEDIATE_VALUE, SET_TRIAL_USER_ATTR, SET_TRIAL_SYSTEM_ATTR)
LAZY_OPS = frozenset({5, 7, 8, 9})


def _complete(line: bytes) -> bool:
    if not line.endswith(b"\n"):
        return False
    try:
        json.loads(line)
    except ValueError:  # JSONDecodeError, UnicodeDecodeError
        return False
    return True


def tail_ok(path) -> bool:
    """Whether the file is empty or ends with a complete record (a quick check)."""
    with open(path, "rb") as fh:
        size = fh.seek(0, os.SEEK_END)
        if size == 0:
            return True
        fh.seek(max(0, size - _TAIL_BYTES))
        tail = fh.read()
    if not tail.endswith(b"\n"):
        return False
    body = tail[:-1]
    cut = body.rfind(b"\n")
    if cut < 0 and size > len(tail):  # a last record longer than what was read: trust it
        return True
    return _complete(body[cut + 1:] + b"\n")


def salvage(data: bytes):
    """``(kept bytes, dropped records, dropped bytes)``: the complete records of ``data``."""
    kept, n_dropped, b_dropped = [], 0, 0
    for line in data.splitlines(keepends=True):
        if _complete(line):
            kept.append(line)
            continue
        start = line.find(RECORD_START, 1)
        while start > 0 and not _complete(line[start:]):
            start = line.find(RECORD_START, start + 1)
        good = line[start:] if start > 0 else b""
        kept.append(good)
        n_dropped += 1
        b_dropped += len(line) - len(good)
    return b"".join(kept), n_dropped, b_dropped


def _backup(path) -> str:
    """Copy the journal to a free ``.bak`` name, atomically: a full disk leaves no partial
    backup (which would push the next repair's backup to ``.1.bak``)."""
    bak, k = f"{path}.bak", 0
    while os.path.exists(bak):
        k += 1
        bak = f"{path}.{k}.bak"
    write_atomic(bak, lambda tmp: shutil.copyfile(path, tmp), what="journal backup")
    return bak


def repair(path) -> str | None:
    """Drop the damaged records of a journal (call it holding the journal lock).

    Returns
    -------
    str or None
        The warning line describing what was dropped, or None when nothing was damaged.

    Raises
    ------
    FuzzynavError
        The repaired file or the backup could not be written (e.g. the disk is still full).
    """
    with open(path, "rb") as fh:
        data = fh.read()
    kept, n, nbytes = salvage(data)
    if n == 0:
        return None
    if not kept and not data.lstrip().startswith(RECORD_START):  # nothing of a journal
        raise FuzzynavError(f"{path}: not an Optuna journal (none of its {len(data)} bytes "
                            "is a journal record); move it away or name another storage")
    # lines that are not even the start of a record: something else wrote into the file
    foreign = sum(1 for line in data.splitlines(keepends=True)
                  if not _complete(line) and not line.startswith(RECORD_START))
    bak = None
    try:
        bak = _backup(path)
        write_atomic(path, lambda tmp: Path(tmp).write_bytes(kept))
    except (OSError, OutputError) as exc:
        if bak is not None:  # the journal is unchanged: its backup would only mislead
            os.unlink(bak)
        why = exc.reason if isinstance(exc, OutputError) else (exc.strerror or exc)
        raise FuzzynavError(f"{path}: the journal has {n} damaged record(s) ({nbytes} bytes) "
                            f"and cannot be repaired: {why}") from None
    n_kept = kept.count(b"\n")
    why = ("a write cut off by a full disk or a killed process" if not foreign else
           f"{foreign} of them not journal records at all: the file was changed by "
           "something other than Optuna")
    return (f"{path}: dropped {n} incomplete record(s) ({nbytes} bytes; {why}), kept "
            f"{n_kept} complete ones; the original is kept as {bak}")


def _repair_locked(path, lock) -> bool:
    from optuna.storages.journal._file import get_lock_file

    with get_lock_file(lock):
        message = repair(path)
    if message is not None:
        print(f"fuzzynav: warning: {message}", file=sys.stderr)
    return message is not None


class SyncOnStateBackend(JournalFileBackend):
    """Optuna's journal file backend, fsyncing only records outside :data:`LAZY_OPS`."""

    def append_logs(self, logs):
        # Optuna's append_logs, with the fsync kept for state changes and creations
        text = "\n".join(json.dumps(log, separators=(",", ":")) for log in logs) + "\n"
        self._lock.acquire()
        try:
            with open(self._file_path, "ab") as fh:
                fh.write(text.encode("utf-8"))
                fh.flush()
                if any(log.get("op_code") not in LAZY_OPS for log in logs):
                    os.fsync(fh.fileno())
        finally:
            self._lock.release()


def open_journal(path):
    """A ``JournalStorage`` on ``path``, its damaged records repaired first (see above)."""
    from optuna.storages.journal import JournalFileSymlinkLock, JournalStorage

    backend = SyncOnStateBackend
    lock = JournalFileSymlinkLock(path)
    if os.path.isfile(path) and not tail_ok(path):
        _repair_locked(path, lock)
    try:
        return JournalStorage(backend(path, lock_obj=lock))
    except ValueError as exc:  # a cut record in the middle (Optuna's replay decode error)
        if not _repair_locked(path, lock):
            raise FuzzynavError(f"{path}: unreadable journal ({exc})") from None
    return JournalStorage(backend(path, lock_obj=lock))
