"""Rewrite the generated results section of a docs page (shared by the paperNNN_results scripts)."""
from __future__ import annotations

from pathlib import Path

from fuzzynav.fileio import publish

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def replace_results(doc: Path, text: str) -> None:
    """Replace what lies between the results markers of ``doc`` with ``text``, atomically."""
    body = doc.read_text()
    body = body.split(BEGIN)[0] + BEGIN + "\n" + text + "\n" + END + body.split(END)[1]
    tmp = doc.with_suffix(".md.tmp")
    tmp.write_text(body)
    publish(tmp, doc)
