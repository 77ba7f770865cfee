"""Publishing files written through a temporary file: the one place for atomic writes.

``tempfile.mkstemp`` creates files readable by their owner only (mode 0600); a rule file, a
figure or a cache file should get the usual mode (0666 minus the umask) like any file the
user writes.  :func:`publish` sets that mode and moves the temporary file into place;
:func:`write_atomic` does the whole round and turns a failure (read-only directory, full
disk) into one :class:`~fuzzynav.errors.OutputError` line, leaving no temporary file.
"""
from __future__ import annotations

import hashlib
import os
import re
import tempfile
from contextlib import contextmanager
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


#: longest name part a derived file name takes from a user-given name (file systems allow
#: 255 bytes per name; the rest carries seeds, hashes and suffixes)
MAX_STEM = 64


def safe_stem(name: str, max_len: int = MAX_STEM) -> str:
    """``name`` as a file-name part: letters, digits, ``-``, ``_`` and ``.``, at most
    ``max_len`` characters (a long name is cut and given a hash of the whole, so two
    long names stay apart)."""
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", name).lstrip(".") or "_"
    if len(stem) <= max_len:
        return stem
    digest = hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()[:8]
    return f"{stem[:max_len - 9]}~{digest}"


@contextmanager
def output_errors(path, what: str):
    """Turn an ``OSError`` while writing ``path`` into one-line :class:`OutputError`.

    Disk full, a read-only file system, no permission, a file where a directory should
    be, a name too long: the message names the file, what it is and the system's reason.
    """
    try:
        yield
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(path, exc, what) from None


def make_dir(path, what: str = "") -> Path:
    """``mkdir -p path``; a failure is an :class:`OutputError` naming it (and ``what``)."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(path, exc, what) from None
    return path


def write_atomic(path, write, suffix: str = ".tmp", what: str = "") -> Path:
    """Write ``path`` by calling ``write(tmp)`` on a temporary file beside it, then publish.

    Parameters
    ----------
    path : str or os.PathLike
    write : callable
        Fills the temporary file given its path (e.g. ``df.to_csv``, ``fig.savefig``).
    suffix : str
        Suffix of the temporary file (writers that infer the format from it need the real one).
    what : str, optional
        What the file is, for the error message ("figure", "report").

    Raises
    ------
    OutputError
        The directory is read-only, the disk full, ...: ``path`` is unchanged and the
        temporary file removed.
    """
    path = Path(path)
    make_dir(path.parent, what)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=suffix)
        os.close(fd)
        write(tmp)
        with open(tmp, "rb+") as fh:  # on disk before it replaces the old file
            os.fsync(fh.fileno())
        publish(tmp, path)
    except OSError as exc:
        raise OutputError(path, exc, what) from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
    return path
