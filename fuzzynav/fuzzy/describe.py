"""Human-readable views of a fuzzy system: the rule grid of a two-input system, rule lines."""
from __future__ import annotations

__all__ = ["rule_grid", "rule_lines", "rule_markdown"]


def rule_grid(fis):
    """``(header, rows)`` of a two-input, one-output table of plain AND rules, else ``None``.

    Rows follow the first input's terms, columns the second's; an empty cell is ``"-"``.
    Systems with NOT, OR, weights other than 1 or partial rules do not fit a grid.
    """
    if len(fis.inputs) != 2 or len(fis.outputs) != 1:
        return None
    a, b = fis.inputs
    cells = {}
    for r in fis.rules:
        conds = {x.variable: x for x in r.antecedents}
        if (r.connective != "and" or len(conds) != 2 or any(x.negated for x in conds.values())
                or r.weight != 1.0):
            return None
        cells[(conds[a.name].term, conds[b.name].term)] = r.consequents[0][1]
    head = [f"{a.name} \\ {b.name}"] + [t.name for t in b.terms]
    return head, [[ta.name] + [cells.get((ta.name, tb.name), "-") for tb in b.terms]
                  for ta in a.terms]


def rule_lines(fis) -> list[str]:
    """One ``if ... then ...`` line per rule (weights other than 1 shown)."""
    out = []
    for r in fis.rules:
        conds = f" {r.connective} ".join(
            f"{x.variable} is {'not ' if x.negated else ''}{x.term}" for x in r.antecedents)
        then = " and ".join(f"{o} is {t}" for o, t in r.consequents)
        w = f" (weight {r.weight:g})" if r.weight != 1.0 else ""
        out.append(f"if {conds} then {then}{w}")
    return out


def rule_markdown(fis) -> str:
    """The rules as a Markdown table (grid) or list."""
    grid = rule_grid(fis)
    if grid is None:
        return "\n".join(f"- {line}" for line in rule_lines(fis))
    head, rows = grid
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows])
