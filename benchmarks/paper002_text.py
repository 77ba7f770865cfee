"""The text of docs/paper002.md around the measured tables (see paper002_results.py)."""
from __future__ import annotations


def page(runs, tables, figs, never, args) -> str:
    parts = ["# Paper 002 reproduced\n"]
    for name, t in tables.items():
        parts.append(f"## {name}\n\n{t}\n\nnever aligned: {never(runs[name][1])}\n")
    for name, f in figs.items():
        parts.append(f"![{name}]({f})\n")
    return "\n".join(parts)
