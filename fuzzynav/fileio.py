"""Publishing files written through a temporary file: the one place for atomic writes.

``tempfile.mkstemp`` creates files readable by their owner only (mode 0600); a rule file, a
figure or a cache file should get the usual mode (0666 minus the umask) like any file the
user writes.  :func:`publish` sets that mode and moves the temporary file into place;
:func:`write_atomic` does the whole round and turns a failure (read-only directory, full
disk) into one :class:`~fuzzynav.errors.OutputError` line, leaving no temporary file.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from fuzzynav.errors import OutputError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: mode of a newly written file: 0666 minus the process umask (read once, at import)
FILE_MODE = 0o666 & ~_umask()


def publish(tmp, path) -> None:
    """Give ``tmp`` the ordinary file mode and ``os.replace`` it onto ``path``."""
    os.chmod(tmp, FILE_MODE)
    os.replace(tmp, path)


def make_dir(path) -> Path:
    """``mkdir -p path``; a failure is an :class:`OutputError` naming it."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(path, exc) from None
    return path


def write_atomic(path, write, suffix: str = ".tmp") -> Path:
    """Write ``path`` by calling ``write(tmp)`` on a temporary file beside it, then publish.

    Parameters
    ----------
    path : str or os.PathLike
    write : callable
        Fills the temporary file given its path (e.g. ``df.to_csv``, ``fig.savefig``).
    suffix : str
        Suffix of the temporary file (writers that infer the format from it need the real one).

    Raises
    ------
    OutputError
        The directory is read-only, the disk full, ...: ``path`` is unchanged and the
        temporary file removed.
    """
    path = Path(path)
    make_dir(path.parent)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=suffix)
        os.close(fd)
        write(tmp)
        with open(tmp, "rb+") as fh:  # on disk before it replaces the old file
            os.fsync(fh.fileno())
        publish(tmp, path)
    except OSError as exc:
        raise OutputError(path, exc) from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
    return path
