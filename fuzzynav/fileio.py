"""Publishing files written through a temporary file: the one place for atomic writes.

``tempfile.mkstemp`` creates files readable by their owner only (mode 0600); a rule file, a
figure or a cache file should get the usual mode (0666 minus the umask) like any file the
user writes.  :func:`publish` sets that mode and moves the temporary file into place;
:func:`write_atomic` does the whole round and turns a failure (read-only directory, full
disk) into one :class:`~fuzzynav.errors.OutputError` line, leaving no temporary file.
:func:`staged` does the same for a group of files (a report directory, a set of rule
files): all are written complete into a temporary directory, then moved into place.
"""
from __future__ import annotations

import hashlib
import math
import os
import re
import shutil
import socket
import tempfile
from contextlib import contextmanager
from pathlib import Path

from fuzzynav.errors import InputFileError, OutputError, brief

__all__ = ["say_written", "write_npz", "FILE_MODE", "publish", "MAX_STEM", "safe_stem", "output_errors", "SYSTEM_DIRS",
           "is_inside", "check_place", "check_output_dir", "study_output", "make_dir", "write_atomic", "write_text_atomic",
           "publish_all", "process_alive", "sweep_staged", "staged", "json_ready"]


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


#: directories of the operating system: fuzzynav writes nothing there, whoever asks (the
#: tests, and many containers, run as root, whom no permission stops)
SYSTEM_DIRS = ("/bin", "/boot", "/dev", "/etc", "/lib", "/lib32", "/lib64", "/proc", "/sbin",
               "/sys", "/usr")


def is_inside(path, base) -> bool:
    """Whether ``path`` is ``base`` or below it, after resolving ``..`` and symbolic links."""
    path, base = Path(os.path.realpath(path)), Path(os.path.realpath(base))
    return path == base or base in path.parents


def check_place(path, what: str = "") -> Path:
    """``path`` unless it lies in a system directory (:data:`SYSTEM_DIRS`): then an
    :class:`OutputError` naming it, before anything is created."""
    for d in SYSTEM_DIRS:
        if os.path.isdir(d) and is_inside(path, d):
            raise OutputError(path, f"{d} is a system directory; fuzzynav writes nothing "
                                    "there", what)
    return Path(path)


def check_output_dir(path, what: str = "") -> Path:
    """``path`` if a directory can be written there, checked before any work and creating
    nothing: not in a system directory, not a file, and below a directory this process may
    write in; else an :class:`OutputError` naming it (and ``what``)."""
    path = check_place(Path(path), what)
    if path.exists() and not path.is_dir():
        raise OutputError(path, "it is a file, not a directory", what)
    parent = path
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(path, f"{parent} cannot be written in", what)
    return path


def study_output(text, study_file, key: str) -> Path:
    """Where a study file's ``key`` says to write: relative to the study's directory and
    inside it (``..`` and symbolic links resolved), else :class:`InputFileError` naming the
    file and key.  Paths given on the command line (``--out``) are the user's own choice
    and do not pass through here."""
    study_file = Path(study_file)
    path = Path(text).expanduser()
    path = path if path.is_absolute() else study_file.parent / path
    if not is_inside(path, study_file.parent):
        raise InputFileError(study_file, key, f"{brief(str(text))} lies outside the study's "
                                              f"directory {study_file.parent}; a study writes "
                                              "only there (give another directory on the "
                                              "command line)")
    return path


def make_dir(path, what: str = "") -> Path:
    """``mkdir -p path``; a failure is an :class:`OutputError` naming it (and ``what``).
    Every writer here passes through it, so none writes into a system directory."""
    path = check_place(Path(path), what)
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


def write_text_atomic(path, text: str, what: str = "") -> Path:
    """Write ``text`` (UTF-8, ``\\n`` line ends) to ``path`` with :func:`write_atomic`."""
    def fill(tmp):
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)

    return write_atomic(path, fill, suffix=Path(path).suffix or ".tmp", what=what)


def publish_all(pairs, what: str = "") -> None:
    """``os.replace`` each ``(source, target)`` pair, in order.

    Parameters
    ----------
    pairs : iterable of (path, path)
        Complete files (on disk, with their final mode) and where they go; each source on
        the same file system as its target, so that each move is one rename.
    what : str, optional
        What the files are, for the error message.

    Raises
    ------
    OutputError
        A rename failed (near impossible once the files are written): it names the target
        that was not replaced and lists the targets already replaced before it.
    """
    done = []
    for source, target in pairs:
        try:
            os.replace(source, target)
        except OSError as exc:
            raise OutputError(target, exc, what, written=done) from None
        done.append(target)


def _renamed(exc: OutputError, tmp: Path, directory: Path) -> OutputError:
    """``exc`` naming the file in ``directory`` that the staged file in ``tmp`` stands for."""
    path = Path(exc.path)
    if path == tmp or tmp in path.parents:
        path = directory / path.relative_to(tmp)
    return OutputError(path, exc.reason, exc.what, written=exc.written)


#: staging directories are named ``.staged-<pid>@<host>-<random>``: the owner is known
_STAGED_RE = re.compile(r"\.staged-(\d+)@([^/]*)-[^-/]+")


def _staged_prefix() -> str:
    return f".staged-{os.getpid()}@{socket.gethostname()}-"


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie -- dead, not yet reaped by its parent -- does
    not: signal 0 still reaches it, so it is told apart by its state in ``/proc``)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            state = fh.read().rsplit(b")", 1)[1].split()[0]
    except (OSError, IndexError):  # no /proc (macOS): signal 0 is all we know
        return True
    return state not in (b"Z", b"X")


def sweep_staged(directory) -> list[Path]:
    """Remove the staging directories in ``directory`` left by a killed writer.

    A process killed (SIGKILL, power loss) inside :func:`staged` cannot clean up; its
    directory is removed by the next writer into the same place, once its owner (a process
    of this host, named in the directory's name) is gone.  Directories of live processes and
    of other hosts (a shared file system) are left alone.

    Returns
    -------
    list of Path
        The directories removed.
    """
    host, removed = socket.gethostname(), []
    for path in Path(directory).glob(".staged-*"):
        m = _STAGED_RE.fullmatch(path.name)
        if m and m.group(2) == host and not process_alive(int(m.group(1))) and path.is_dir():
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


@contextmanager
def staged(directory, what: str = "", last=()):
    """Write a group of files into ``directory`` all at once, or not at all.

    Yields a temporary directory inside ``directory`` (so every move is a rename on one
    file system); the caller writes its files there, complete.  When the block ends, every
    file in it is moved onto the same name in ``directory`` (the names in ``last`` after the
    others: an index such as ``report.md`` appears once what it refers to is there); the
    temporary directory is removed in any case, and one a killed writer left behind is
    removed by the next (:func:`sweep_staged`).

    Parameters
    ----------
    directory : str or os.PathLike
        Created if missing.
    what : str, optional
        What the files are, for the error message.
    last : sequence of str
        File names to move after all others.

    Raises
    ------
    OutputError
        The block failed writing a file (named by its final name in ``directory``), the
        temporary directory could not be made, or a final rename failed (the message then
        lists the files moved before it).  Otherwise ``directory`` is as it was.
    """
    directory = make_dir(directory, what)
    sweep_staged(directory)
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_staged_prefix(), dir=directory))
    except OSError as exc:  # a read-only directory
        raise OutputError(directory, exc, what) from None
    try:
        yield tmp
        names = sorted((p.name for p in tmp.iterdir()), key=lambda n: (n in last, n))
        publish_all([(tmp / n, directory / n) for n in names], what)
    except OutputError as exc:
        raise _renamed(exc, tmp, directory) from None
    except OSError as exc:
        raise OutputError(directory, exc, what) from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def say_written(path, json_on_stdout: bool = False) -> None:
    """Print ``wrote PATH`` for a file a command wrote: on stdout, or on stderr when stdout
    carries the command's JSON (``--json --plot``), which must stay one JSON document."""
    import sys

    print(f"wrote {path}", file=sys.stderr if json_on_stdout else sys.stdout)


def json_ready(x):
    """``x`` with NaN and infinities as ``None``, recursively through dicts, lists and
    tuples (JSON has no NaN; a metric that may legitimately be NaN is written as null)."""
    if isinstance(x, dict):
        return {k: json_ready(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_ready(v) for v in x]
    return None if isinstance(x, float) and not math.isfinite(x) else x


def write_npz(path, arrays: dict, what: str) -> None:
    """Write ``arrays`` to the ``.npz`` file ``path`` atomically (a temporary file beside it,
    then renamed: a reader never sees half a file); a full disk or a read-only place is one
    :class:`OutputError` naming ``what``, with an old file left intact."""
    import numpy as np

    path = Path(path)
    make_dir(path.parent, what)
    with output_errors(path, what):
        fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez(f, **arrays)
            publish(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
