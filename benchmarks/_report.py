"""Shared helpers of the benchmarks: machine description and docs/benchmarks.md sections."""
from __future__ import annotations

import datetime as _dt
import os
import platform
import tempfile
from pathlib import Path

from fuzzynav.fileio import publish

DOC = Path(__file__).resolve().parents[1] / "docs" / "benchmarks.md"
HEADER = """# Benchmarks

Speed is measured here, never asserted in tests. Each section is written by the script named
in it (run it from the repository root with the `[dev]` extras installed); a script rewrites only
its own section, between its markers. Figures are from one run on the machine described in the
section; rerun the script to refresh them.
"""


def machine() -> str:
    """One line describing the CPU, core count, Python and key library versions."""
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


def write_section(name: str, body: str) -> None:
    """Replace (or append) the section ``name`` of docs/benchmarks.md, atomically."""
    begin, end = f"<!-- bench:{name}:begin -->", f"<!-- bench:{name}:end -->"
    text = DOC.read_text() if DOC.exists() else HEADER
    block = f"{begin}\n{body.rstrip()}\n{end}"
    if begin in text and end in text:
        head, rest = text.split(begin, 1)
        text = head + block + rest.split(end, 1)[1]
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    DOC.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=DOC.parent, prefix=".benchmarks.", suffix=".md")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    publish(tmp, DOC)


def write_results(doc: Path, body: str) -> None:
    """Replace the text between ``<!-- results:begin -->`` and ``<!-- results:end -->`` of
    a docs page (e.g. docs/paper004.md), atomically."""
    a, b = "<!-- results:begin -->", "<!-- results:end -->"
    text = doc.read_text()
    text = text.split(a)[0] + a + "\n" + body + "\n" + b + text.split(b)[1]
    fd, tmp = tempfile.mkstemp(dir=doc.parent, prefix=f".{doc.stem}.", suffix=".md")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    publish(tmp, doc)
