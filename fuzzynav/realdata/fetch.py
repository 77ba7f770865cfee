"""Downloading the public recordings (``fuzzynav data fetch NAME``) with pooch.

Each file of a dataset (:data:`fuzzynav.realdata.datasets.DATASETS`) is downloaded from
``BASE_URL + file.url`` -- the raw-file host of GitHub at a fixed commit, or
``$FUZZYNAV_DATA_URL`` when set (a mirror, or the tests' local server) -- into
``DEST/NAME/file.path`` (``DEST``: ``--dest``, else :func:`~fuzzynav.realdata.datasets.fetch_home`).

pooch streams each file into a temporary file beside its target, checks its SHA-256
against the pinned one and only then moves it into place, so nothing half-written is ever
at a target path.  A file already there is hashed: kept when it matches, downloaded again
when it does not (an interrupted earlier copy, a damaged file).  So an interrupted fetch
resumes file by file: rerunning it downloads only what is missing or wrong (a file is not
resumed mid-way: pooch does no HTTP range requests).  A download whose hash does not
match is refused; nothing of it is left, and a wrong file already at the target is removed.
"""
from __future__ import annotations

import contextlib
import logging
import os
from pathlib import Path

from fuzzynav.errors import DataMissingError, OutputError, UnknownNameError
from fuzzynav.fileio import make_dir
from fuzzynav.realdata.datasets import DATASETS, Dataset, fetch_home

__all__ = ["DATA_URL_ENV", "DEFAULT_BASE_URL", "RETRIES", "TIMEOUT_S", "FetchError",
           "base_url", "get_dataset", "fetch", "dataset_status"]

#: environment variable replacing :data:`DEFAULT_BASE_URL` (a mirror laid out alike)
DATA_URL_ENV = "FUZZYNAV_DATA_URL"
#: where the registry's URL paths are relative to: ``owner/repo/commit/path``
DEFAULT_BASE_URL = "https://raw.githubusercontent.com/"
#: further attempts after a failed download of a file (pooch waits 1 s, 2 s, ... between)
RETRIES = 2
#: seconds without an answer before a download is given up
TIMEOUT_S = 60.0


class FetchError(DataMissingError):
    """A dataset could not be downloaded (no network, a server error, a wrong hash)."""


def base_url() -> str:
    """``$FUZZYNAV_DATA_URL`` or :data:`DEFAULT_BASE_URL`, ending with ``/``."""
    url = os.environ.get(DATA_URL_ENV) or DEFAULT_BASE_URL
    return url if url.endswith("/") else url + "/"


def get_dataset(name: str) -> Dataset:
    """The registered dataset ``name`` (an unknown one is one error listing the known)."""
    if name not in DATASETS:
        raise UnknownNameError("dataset", name, DATASETS)
    return DATASETS[name]


def _reason(exc) -> str:
    """A short reason for a failed request (requests' own messages run over lines)."""
    import requests

    if isinstance(exc, requests.HTTPError) and exc.response is not None:
        return f"HTTP {exc.response.status_code}"
    if isinstance(exc, requests.Timeout):
        return f"no answer within {TIMEOUT_S:g} s"
    if isinstance(exc, requests.ConnectionError):
        return "no connection to the server"
    return exc.__class__.__name__


def _offline_message(ds: Dataset, url: str, reason: str, target_dir: Path) -> str:
    return (f"{ds.name}: cannot download {url} ({reason}): without network, download the "
            f"files of `fuzzynav data list {ds.name} --files` (from {ds.source}) into "
            f"{target_dir}/, then run `fuzzynav data fetch {ds.name}` to check their hashes")


@contextlib.contextmanager
def _quiet_pooch():
    """pooch logs every download at INFO on stderr; the caller reports instead."""
    import pooch

    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel(logging.WARNING)
    try:
        yield
    finally:
        logger.setLevel(level)


@contextlib.contextmanager
def _no_empty_directory(path: Path, created=()):
    """Remove ``path`` afterwards if it is left empty, and the directories of ``created``
    (made for it, deepest first) that are left empty too: a fetch that failed at once
    leaves no sign of a dataset, so ``data list`` and ``--data`` still say to fetch it."""
    try:
        yield
    finally:
        for d in dict.fromkeys([path, *created]):
            with contextlib.suppress(OSError):
                if d.is_dir() and not any(d.iterdir()):
                    d.rmdir()


def _fetcher(ds: Dataset, home: Path, url: str, retries: int):
    import pooch

    return pooch.create(path=home, base_url=url,
                        registry={f"{ds.name}/{f.path}": f"sha256:{f.sha256}" for f in ds.files},
                        urls={f"{ds.name}/{f.path}": url + f.url for f in ds.files},
                        retry_if_failed=retries)


def _holds(path: Path, sha256: str) -> bool:
    """Whether ``path`` is a file with that SHA-256."""
    import pooch

    return path.is_file() and pooch.file_hash(str(path)) == sha256


def _drop_if_wrong(path: Path, sha256: str) -> None:
    """Remove ``path`` if it exists with another hash (a wrong copy must not stay)."""
    if path.is_file() and not _holds(path, sha256):
        path.unlink()


def fetch(name: str, dest=None, url: str | None = None, retries: int | None = None,
          echo=print) -> Path:
    """Download dataset ``name`` (module docstring) and return its directory.

    Parameters
    ----------
    name : str
        A key of :data:`DATASETS` (``akit``, ``rtklib-drive``).
    dest : path-like, optional
        The data directory to write into (``DEST/NAME/...``); default
        :func:`~fuzzynav.realdata.datasets.fetch_home`.
    url : str, optional
        Base URL (default :func:`base_url`).
    retries : int, optional
        Further attempts per file (default :data:`RETRIES`).
    echo : callable
        Called with one line per file (``downloaded`` or ``present``).

    Raises
    ------
    FetchError
        No network or a server error (one line: what to download, where to put it), or a
        download whose hash does not match (nothing of it is kept).
    OutputError
        The data directory cannot be made or written, or is a system directory.
    """
    import pooch
    import requests

    ds = get_dataset(name)
    home = Path(dest).expanduser() if dest is not None else fetch_home()
    url = base_url() if url is None else (url if url.endswith("/") else url + "/")
    target_dir = (home / ds.name).absolute()
    created = [d for d in (target_dir, *target_dir.parents) if not d.exists()]
    make_dir(target_dir, "data directory")   # (refuses a system directory, names a failure)
    getter = _fetcher(ds, home, url, RETRIES if retries is None else int(retries))
    downloader = pooch.HTTPDownloader(timeout=TIMEOUT_S, progressbar=False)
    with _quiet_pooch(), _no_empty_directory(target_dir, created):
        for f in ds.files:
            target = home / ds.name / f.path
            if _holds(target, f.sha256):
                echo(f"{ds.name}/{f.path}: present, hash checked")
                continue
            try:
                getter.fetch(f"{ds.name}/{f.path}", downloader=downloader)
            except requests.RequestException as exc:
                raise FetchError(_offline_message(ds, url + f.url, _reason(exc),
                                                  target.parent)) from None
            except ValueError:  # pooch: the downloaded file's hash is not the pinned one
                _drop_if_wrong(target, f.sha256)
                raise FetchError(f"{ds.name}: {url + f.url}: the download's SHA-256 is not "
                                 f"the pinned {f.sha256[:12]}... (a changed or damaged "
                                 f"file): refused, nothing kept at {target}") from None
            except OSError as exc:
                raise OutputError(target, exc, "data file") from None
            echo(f"{ds.name}/{f.path}: downloaded ({f.size_bytes / 1e6:.2f} MB)")
    return home / ds.name


def dataset_status(ds: Dataset):
    """``(directory or None, number of files missing or of the wrong size)`` where the
    lookup finds ``ds`` (no hashing: ``fetch`` checks hashes)."""
    from fuzzynav.realdata.datasets import find_directory

    path = find_directory(ds.name)
    return path, len(ds.files) if path is None else len(ds.missing_files(path))
