"""Recording kinds usable with ``--data KIND:DIR[:SESSION]`` and the parsing of that argument.

``--data NAME[:SESSION]`` names a public dataset instead (``rtklib-drive``, ``akit:3``;
:mod:`fuzzynav.realdata.datasets`), found where ``fuzzynav data fetch NAME`` put it.

A kind is one :class:`DataSource` in :data:`SOURCES`: a description and a loader taking the
recording directory (any copy of a recording of that kind) and returning an object with
``imu`` (:class:`~fuzzynav.sim.imu.ImuData`), ``gnss`` (all fixes, kind ``gnss``),
``reference`` (the untouched fixes used as truth), ``mounting`` (or ``None``) and
``directory`` — the :class:`~fuzzynav.realdata.loaders.rtklib.Recording` of the RTKLIB loader.
Add a kind with :func:`register_source`.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from fuzzynav.errors import DataMissingError, FuzzynavError, UnknownNameError

__all__ = ["DataSource", "SOURCES", "register_source", "MOUNTINGS_DIR", "builtin_mountings",
           "resolve_mounting", "split_options", "data_options", "split_dataset_spec",
           "parse_data_spec"]


@dataclass(frozen=True)
class DataSource:
    """One kind of recording.

    Attributes
    ----------
    kind : str
        The name before the colon of ``--data KIND:DIR``.
    description : str
        One line for ``fuzzynav scenarios``.
    load : callable
        ``load(directory, mounting="auto", imu_delay_s=None, span_s=None, session=None,
        options=None, streamed=False) -> Recording``; ``None`` leaves a loader's own
        default (``session``: which recording of a directory that holds several;
        ``options``: the :class:`~fuzzynav.realdata.start_options.StartOptions` of a
        ``?key=value`` suffix; ``streamed``: keep the IMU in its file and read it chunk by
        chunk when run, where the kind can — rtklib; A-KIT trajectories are held).
    split : callable or None
        ``split(session) -> [session, ...]`` for a kind whose ``SESSION`` may name several
        recordings (A-KIT ``1-4``); a study runs each separately.
    """

    kind: str
    description: str
    load: Callable
    split: Callable | None = None
    #: ``module:Class`` of the run source its recordings are run as
    #: (:mod:`fuzzynav.runpath`); its ``SETTINGS`` say which run settings apply
    run_source: str = "fuzzynav.realdata.session:GnssSource"

    def source_type(self) -> type:
        """The run source class of this kind (imported on demand: it pulls the filters)."""
        module, name = self.run_source.split(":")
        return getattr(importlib.import_module(module), name)


SOURCES: dict[str, DataSource] = {}


def register_source(kind: str, description: str, split: Callable | None = None,
                    run_source: str = DataSource.run_source):
    """Decorator registering a loader function under ``kind`` (``split``, ``run_source``:
    see :class:`DataSource`)."""

    def deco(fn):
        SOURCES[kind] = DataSource(kind, description, fn, split, run_source)
        return fn

    return deco


@register_source("rtklib", "RTKLIB car recording: imu_<id>.csv + .tag + gnss_<id>*.pos "
                           "(e.g. --data rtklib-drive, after fuzzynav data fetch rtklib-drive)")
def _load_rtklib(directory, mounting="auto", imu_delay_s=None, span_s=None, session=None,
                 options=None, streamed=False):
    from fuzzynav.realdata.loaders.rtklib import load_rtklib

    kw = {} if imu_delay_s is None else {"imu_delay_s": float(imu_delay_s)}
    # velocities are loaded as recorded; the protocol decides what to do with their lag
    return load_rtklib(directory, mounting=mounting, span_s=span_s, session=session,
                       start=options, streamed=streamed, **kw)


def _akit_split(session):
    from fuzzynav.realdata.loaders.akit_recording import parse_trajectories

    return parse_trajectories(session)


@register_source("akit", "A-KIT AUV recordings: IMU/DVL/GT_trajectoryN.csv + corrected/ "
                         "(akit:DIR:N, N = 3, 1-8 or 1,4; e.g. --data akit:3 after "
                         "fuzzynav data fetch akit)",
                 split=_akit_split, run_source="fuzzynav.realdata.akit:AkitSource")
def _load_akit(directory, mounting="auto", imu_delay_s=None, span_s=None, session=None,
               options=None, streamed=False):  # held: a trajectory's files are small
    from fuzzynav.realdata.akit import AkitSource
    from fuzzynav.runpath import refuse_settings
    from fuzzynav.realdata.loaders.akit_recording import load_akit

    given = {"mounting": "--mounting"} if mounting not in ("auto", None) else {}
    given.update({"imu_delay": "--imu-delay"} if imu_delay_s is not None else {})
    refuse_settings(AkitSource, {**given, **({"span": "--span"} if span_s is not None else {})})
    if options is not None:
        raise FuzzynavError("--data akit: ?options do not apply (the filter starts from the "
                            "reference, not from a rest and a GNSS course)")
    return load_akit(directory, session)


#: mounting files shipped with the package (``--mounting NAME``)
MOUNTINGS_DIR = Path(__file__).resolve().parent / "mountings"


def builtin_mountings() -> list[str]:
    """Names of the shipped mounting files (``rtklib-drive``, ...)."""
    return sorted(p.stem for p in MOUNTINGS_DIR.glob("*.toml"))


def resolve_mounting(text):
    """``--mounting`` value to a loader argument: ``"auto"``, ``None`` or a file path.

    ``auto`` (or nothing) reads ``mounting.toml`` beside the data if present; ``none`` uses
    the IMU frame; otherwise an existing file, else a shipped name (:func:`builtin_mountings`).
    """
    if text is None or text == "auto":
        return "auto"
    if text.lower() == "none":
        return None
    path = Path(text).expanduser()
    if path.is_file():
        return path
    if (MOUNTINGS_DIR / f"{text}.toml").is_file():
        return MOUNTINGS_DIR / f"{text}.toml"
    raise DataMissingError(f"{text}: mounting file not found (nor a shipped mounting: "
                           f"{', '.join(builtin_mountings())}; or auto, none)")


def _is_dir(path: Path) -> bool:
    """``path.is_dir()``, False where the system refuses to look (a name too long)."""
    try:
        return path.is_dir()
    except OSError:
        return False


def split_options(spec: str) -> tuple[str, str | None]:
    """``KIND:DIR[:SESSION][?OPTIONS]`` -> (the spec without options, the options or None).

    A ``?`` that belongs to an existing directory's name is kept in it.
    """
    head, mark, query = str(spec).rpartition("?")
    rest = str(spec).partition(":")[2]   # (an empty one is no directory: rtklib-drive?...)
    if not mark or (rest and _is_dir(Path(rest).expanduser())):
        return str(spec), None
    return head, query


def data_options(spec: str):
    """The :class:`~fuzzynav.realdata.start_options.StartOptions` of a data spec's ``?key=value``
    suffix, or ``None`` without one (the loader's defaults)."""
    from fuzzynav.realdata.start_options import parse_start_options

    bare, query = split_options(spec)
    return None if query is None else parse_start_options(query, bare)


def split_dataset_spec(body: str, directory_exists=_is_dir):
    """``NAME[:SESSION]`` of a registered dataset -> ``(kind, name, session)``; ``None``
    when ``body`` (a spec without ``?options`` and ``@window``) is not of that form.

    A dataset named like its kind (``akit``) is the dataset only when what follows the
    colon is a valid session of the kind (``akit:3``, ``akit:1-4``) that
    ``directory_exists`` denies, so ``akit:DIR`` and ``akit:DIR:N`` keep their meaning.
    """
    from fuzzynav.realdata.datasets import DATASETS

    name, sep, rest = body.partition(":")
    ds = DATASETS.get(name)
    if ds is None:
        return None
    if sep and name in SOURCES:
        split = SOURCES[name].split
        if split is None or ":" in rest or not rest or directory_exists(Path(rest).expanduser()):
            return None
        try:
            split(rest)
        except FuzzynavError:
            return None
    return ds.kind, name, (rest if sep else None)


def _dataset(spec: str, short) -> tuple:
    """(source, directory, session) of a dataset spec; a missing one names ``--data``."""
    from fuzzynav.realdata.datasets import locate

    kind, name, session = short
    if session == "":
        raise FuzzynavError(f"--data {spec}: empty session after {name}:")
    try:
        return SOURCES[kind], locate(name), session
    except DataMissingError as exc:
        raise DataMissingError(f"--data {spec}: {exc}") from None


def parse_data_spec(spec: str) -> tuple[DataSource, Path, str | None]:
    """Split ``KIND:DIR[:SESSION][?OPTIONS]`` or ``NAME[:SESSION][?OPTIONS]`` (a dataset,
    :func:`split_dataset_spec`) and check the parts (the options are read by
    :func:`data_options`).

    ``SESSION`` chooses one recording of a directory that holds several (for ``rtklib``
    the ``<id>`` of ``imu_<id>.csv``).  A directory whose own name has a colon is taken
    whole when it exists.

    Returns
    -------
    source : DataSource
    directory : Path
    session : str or None

    Raises
    ------
    FuzzynavError
        Without a colon or with an empty part.
    UnknownNameError
        For a kind not in :data:`SOURCES`.
    DataMissingError
        When the directory does not exist, or the dataset is not found (the message says
        ``fuzzynav data fetch NAME``).
    """
    spec = split_options(spec)[0]
    short = split_dataset_spec(spec)
    if short is not None:
        return _dataset(spec, short)
    kind, sep, rest = spec.partition(":")
    directory, session = rest, None
    head, colon, tail = rest.rpartition(":")
    if colon and not _is_dir(Path(rest).expanduser()):
        directory, session = head, tail
    if not sep and kind and kind not in SOURCES and not _is_dir(Path(kind).expanduser()) \
            and "/" not in kind:  # a bare word, no directory: a dataset's name, misspelt
        from fuzzynav.realdata.datasets import DATASETS

        raise UnknownNameError("dataset", kind, DATASETS)
    if not sep or not kind or not directory or session == "":
        raise FuzzynavError(f"--data: expected KIND:DIR, KIND:DIR:SESSION or a dataset "
                            f"NAME[:SESSION] (e.g. rtklib:path/to/drive, rtklib-drive or "
                            f"akit:3; fuzzynav data list), got {spec!r}")
    if kind not in SOURCES:
        raise UnknownNameError("data source kind", kind, SOURCES)
    path = Path(directory).expanduser()
    if not _is_dir(path):
        raise DataMissingError(f"{path}: recording directory not found (--data {spec})")
    return SOURCES[kind], path, session
