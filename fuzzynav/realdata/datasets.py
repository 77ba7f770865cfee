"""The public recordings fuzzynav knows by name, and where their copies are looked for.

:data:`DATASETS` is read from ``datasets.json`` beside this module (built by
``tools/data_registry.py``): each dataset's recording kind and its files, with the
URL path of each at a fixed upstream commit and its SHA-256.  ``fuzzynav data fetch NAME``
(:mod:`fuzzynav.realdata.fetch`) downloads them; ``--data NAME`` (``--data akit:N``,
``--data rtklib-drive``) and the study specs then find them.

Where a recording named by a dataset name or a relative directory is looked for, in order
(an explicit path, ``--data rtklib:/some/dir``, is read where it is):

1. ``$FUZZYNAV_DATA`` when it is set -- then the only place, and where ``fetch`` writes;
2. the user cache, ``pooch.os_cache("fuzzynav")`` (``~/.cache/fuzzynav`` on Linux), where
   ``fetch`` writes by default;
3. ``../shared/datasets`` beside the repository, when it exists (the maintainers'
   development workspace; a user's machine has none).

Of several places holding a dataset's directory the first with every file (by size) wins,
else the first with the directory.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.errors import DataMissingError, InputFileError

__all__ = ["DATA_DIR_ENV", "DEV_DATA_DIR", "REGISTRY_FILE", "DataFile", "Dataset",
           "load_registry", "DATASETS", "user_cache_dir", "dev_data_dir", "data_dirs",
           "fetch_home", "find_directory", "missing_dataset_message", "locate"]

#: environment variable naming the data directory (overrides the user cache)
DATA_DIR_ENV = "FUZZYNAV_DATA"
#: the maintainers' data directory, relative to the repository (the package's parent)
DEV_DATA_DIR = Path("..") / "shared" / "datasets"
#: the registry shipped with the package
REGISTRY_FILE = Path(__file__).resolve().with_name("datasets.json")
_DATASET_KEYS = ("kind", "description", "source", "licence", "files")
_FILE_KEYS = ("path", "url", "sha256", "size_bytes")


@dataclass(frozen=True)
class DataFile:
    """One file of a dataset: ``path`` inside the dataset directory, ``url`` relative to the
    download host, its SHA-256 (hex) and size."""

    path: str
    url: str
    sha256: str
    size_bytes: int


@dataclass(frozen=True)
class Dataset:
    """A named public recording (module docstring)."""

    name: str
    kind: str
    description: str
    source: str
    licence: str
    files: tuple

    @property
    def size_bytes(self) -> int:
        """Total size of its files."""
        return sum(f.size_bytes for f in self.files)

    def missing_files(self, directory: Path) -> list:
        """The files absent from ``directory`` or of the wrong size (no hashing)."""
        out = []
        for f in self.files:
            p = directory / f.path
            if not p.is_file() or p.stat().st_size != f.size_bytes:
                out.append(f)
        return out


def _checked_file(path, where: str, entry) -> DataFile:
    if not isinstance(entry, dict) or set(entry) != set(_FILE_KEYS):
        raise InputFileError(path, where, f"expected an object with keys {', '.join(_FILE_KEYS)}")
    rel = entry["path"]
    if not isinstance(rel, str) or not rel or rel.startswith("/") or ".." in rel.split("/"):
        raise InputFileError(path, f"{where}.path", f"not a relative path inside the dataset: "
                                                    f"{rel!r}")
    sha = entry["sha256"]
    if not isinstance(sha, str) or len(sha) != 64 or any(c not in "0123456789abcdef" for c in sha):
        raise InputFileError(path, f"{where}.sha256", "expected 64 lower-case hex digits")
    size = entry["size_bytes"]
    if not isinstance(size, int) or isinstance(size, bool) or size < 0:
        raise InputFileError(path, f"{where}.size_bytes", "expected a non-negative integer")
    if not isinstance(entry["url"], str) or not entry["url"]:
        raise InputFileError(path, f"{where}.url", "expected a non-empty string")
    return DataFile(rel, entry["url"], sha, size)


def load_registry(path=REGISTRY_FILE) -> dict:
    """``{name: Dataset}`` from a registry file (every field checked).

    Raises
    ------
    InputFileError
        Naming the file and the field at fault.
    """
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise InputFileError(path, "", f"cannot be read as JSON ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("datasets"), dict):
        raise InputFileError(path, "$.datasets", "expected an object of datasets")
    out = {}
    for name, d in doc["datasets"].items():
        where = f"$.datasets.{name}"
        if not isinstance(d, dict) or set(d) != set(_DATASET_KEYS):
            raise InputFileError(path, where, f"expected keys {', '.join(_DATASET_KEYS)}")
        if not isinstance(d["files"], list) or not d["files"]:
            raise InputFileError(path, f"{where}.files", "expected a non-empty array")
        files = tuple(_checked_file(path, f"{where}.files[{i}]", e)
                      for i, e in enumerate(d["files"]))
        out[name] = Dataset(name, str(d["kind"]), str(d["description"]), str(d["source"]),
                            str(d["licence"]), files)
    return out


#: the datasets shipped in the registry, by name
DATASETS: dict = load_registry()


def user_cache_dir() -> Path:
    """The user cache fuzzynav downloads into (``pooch.os_cache("fuzzynav")``)."""
    import pooch

    return Path(pooch.os_cache("fuzzynav"))


def dev_data_dir() -> Path | None:
    """``../shared/datasets`` beside the repository if it exists, else ``None``."""
    path = (Path(__file__).resolve().parents[2] / DEV_DATA_DIR).resolve()
    return path if path.is_dir() else None


def data_dirs() -> list:
    """The places relative recording directories are looked for, in order (module
    docstring): ``[$FUZZYNAV_DATA]`` alone when set, else the user cache and the
    maintainers' directory if it exists."""
    env = os.environ.get(DATA_DIR_ENV)
    if env:
        return [Path(env).expanduser()]
    dev = dev_data_dir()
    return [user_cache_dir()] + ([dev] if dev is not None else [])


def fetch_home() -> Path:
    """Where ``fuzzynav data fetch`` writes: ``$FUZZYNAV_DATA`` if set, else the user
    cache."""
    return data_dirs()[0]


def find_directory(relative) -> Path | None:
    """The first ``base / relative`` of :func:`data_dirs` that is a directory; for a
    dataset name, the first holding all of its files, if any does."""
    found = [b / relative for b in data_dirs() if (b / relative).is_dir()]
    ds = DATASETS.get(str(relative))
    if ds is not None:
        for path in found:
            if not ds.missing_files(path):
                return path
    return found[0] if found else None


def missing_dataset_message(name: str) -> str:
    """One line: the dataset is not here, how to get it, where to put it."""
    looked = ", ".join(str(b) for b in data_dirs())
    return (f"dataset {name!r} not found (looked in {looked}): run `fuzzynav data fetch "
            f"{name}`, or put its files (`fuzzynav data list {name} --files`) in "
            f"{fetch_home() / name} or set {DATA_DIR_ENV} to a directory holding {name}/")


def locate(name: str) -> Path:
    """The directory of dataset ``name`` (:func:`find_directory`).

    Raises
    ------
    DataMissingError
        When no place holds it (:func:`missing_dataset_message`).
    """
    path = find_directory(name)
    if path is None:
        raise DataMissingError(missing_dataset_message(name))
    return path
