"""Shared helpers of the speed benchmarks: their sections of docs/benchmarks.md."""
from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

from fuzzynav.fileio import write_text_atomic
from fuzzynav.pages.common import machine, markers, replace_section

__all__ = ["machine", "write_section", "measured_section", "bench_parser"]

DOC = Path(__file__).resolve().parents[1] / "docs" / "benchmarks.md"
HEADER = """# Benchmarks

Speed is measured here, never asserted in tests. Each section is written by the script named
in it (run it from the repository root with the `[dev]` extras installed); a script rewrites only
its own section, between its markers. Figures are from one run on the machine described in the
section; rerun the script to refresh them.
"""


def write_section(name: str, body: str) -> None:
    """Replace (or append) the section ``name`` of docs/benchmarks.md, atomically."""
    begin, end = markers(f"bench:{name}")
    text = DOC.read_text() if DOC.exists() else HEADER
    if begin not in text or end not in text:
        text = text.rstrip() + f"\n\n{begin}\n{end}\n"
    write_text_atomic(DOC, replace_section(text, f"bench:{name}", body.rstrip()))


def measured_section(name: str, args, measure_all, report) -> str:
    """Run ``measure_all(tmp)`` in a fresh temporary directory (removed after), then
    ``report(args, rounds, (load at start, load at end), seconds)``; print the text and,
    unless ``args.no_write``, write it as section ``name``.  Returns the text."""
    t0, load0 = time.monotonic(), os.getloadavg()[0]
    tmp = Path(tempfile.mkdtemp(prefix=f"bench-{name}-"))
    try:
        rounds = measure_all(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    text = report(args, rounds, (load0, os.getloadavg()[0]), time.monotonic() - t0)
    print(text)
    if not args.no_write:
        write_section(name, text)
    return text


def bench_parser(doc: str, **counts: int) -> argparse.ArgumentParser:
    """The command line of a benchmark: ``--no-write`` and one integer option per entry of
    ``counts`` (``long_trials=3`` is ``--long-trials``, default 3); described by the first
    line of ``doc``."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    for name, default in counts.items():
        ap.add_argument("--" + name.replace("_", "-"), type=int, default=default)
    ap.add_argument("--no-write", action="store_true", help="print, leave docs/ alone")
    return ap
