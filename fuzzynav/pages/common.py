"""What every docs page generator shares: the machine line, the count of runs that
stopped early and the atomic section rewrite."""
from __future__ import annotations

import datetime as _dt
import os
import platform
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.fileio import write_text_atomic

__all__ = ["REPO_ROOT", "PageContext", "machine", "stopped_early", "markers", "replace_section",
           "write_section"]

#: the repository root (docs/, rules/, studies/ live here in a source checkout)
REPO_ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class PageContext:
    """Where a generator reads and writes.

    Attributes
    ----------
    root : Path
        Repository root (``docs/``, ``rules/``, ``studies/``).
    fig_dir : Path
        Directory the page's figures are written to (``docs/figures`` for the docs page).
    cache : Path
        Simulation cache directory.
    data_dir : Path
        Directory of the recordings (``$FUZZYNAV_DATA``, else ``../shared/datasets``).
    command : str
        The command line that made the page, quoted on it.
    """

    root: Path
    fig_dir: Path
    cache: Path
    data_dir: Path
    command: str


def machine() -> str:
    """One line describing the CPU, core count, Python and key library versions, and today."""
    import numba
    import numpy

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, "
            f"numpy {numpy.__version__}, numba {numba.__version__}; "
            f"{_dt.date.today().isoformat()}")


def stopped_early(dfs: dict) -> str:
    """``"name n, ..."``: per scenario (``dfs``: name -> runs with ``completed``), how many
    runs stopped before the end (``completed`` < 1), zeros included."""
    return ", ".join(f"{k} {int((df['completed'] < 1).sum())}" for k, df in dfs.items())


def markers(marker: str) -> tuple[str, str]:
    """The begin and end comment lines of the marked section ``marker``."""
    return f"<!-- {marker}:begin -->", f"<!-- {marker}:end -->"


def replace_section(text: str, marker: str | None, body: str, where: str = "page") -> str:
    """``text`` with the section between the ``marker`` comments replaced by ``body``
    (``marker`` None: ``body`` is the whole page).

    Raises
    ------
    FuzzynavError
        ``text`` lacks the begin or the end marker.
    """
    if marker is None:
        return body
    begin, end = markers(marker)
    if begin not in text or end not in text:
        raise FuzzynavError(f"{where}: no section {begin} ... {end} to rewrite")
    head, rest = text.split(begin, 1)
    return head + begin + "\n" + body + "\n" + end + rest.split(end, 1)[1]


def write_section(doc: Path, marker: str | None, body: str, source: Path | None = None) -> None:
    """Rewrite the section ``marker`` of the page ``source`` (default ``doc``) into ``doc``
    atomically (``marker`` None: ``body`` is the whole page); a page without the section is
    an error and nothing is written."""
    source = Path(source or doc)
    old = source.read_text(encoding="utf-8") if marker is not None else ""
    write_text_atomic(Path(doc), replace_section(old, marker, body, where=str(source)))
