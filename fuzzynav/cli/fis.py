"""``fuzzynav fis``: look at, check and convert fuzzy rule files.

* ``fuzzynav fis surface FILE [--grid N] [--output NAME] [--at NAME=VALUE] [--csv]``
  evaluates the system on a grid over its input ranges and prints the control surface;
* ``fuzzynav fis check FILE`` validates and prints a one-screen summary;
* ``fuzzynav fis convert IN OUT`` converts between JSON and MATLAB ``.fis`` (by extension).
"""
from __future__ import annotations

import argparse
import csv
import math
import sys

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.fuzzy.describe import rule_grid

__all__ = ["register", "cmd_surface", "cmd_check", "cmd_convert"]

_FORMATS = {".json": "fuzzynav-fis JSON", ".fis": "MATLAB .fis"}


def _grid_size(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if not 2 <= n <= 1001:
        raise argparse.ArgumentTypeError(f"grid size must be 2..1001, got {n}")
    return n


def _assignment(text: str):
    name, sep, value = text.partition("=")
    try:
        if not sep:
            raise ValueError
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}") from None
    if not math.isfinite(number):  # would print a table of NaN as if it were a surface
        raise argparse.ArgumentTypeError(f"VALUE must be a finite number, got {text!r}")
    return name.strip(), number


def register(subparsers) -> None:
    """Add the ``fis`` command group to the ``fuzzynav`` parser."""
    p = subparsers.add_parser("fis", help="inspect, check and convert fuzzy rule files",
                              description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="fis_command", metavar="SUBCOMMAND")
    sub.required = True

    s = sub.add_parser("surface", help="print the control surface of a rule file",
                       description="Evaluate the rule file (exact mode) on a grid over its "
                                   "input ranges and print the control surface.")
    s.add_argument("file", metavar="FILE", help="rule file (.json or MATLAB .fis)")
    s.add_argument("--grid", type=_grid_size, default=9, metavar="N",
                   help="points per input axis (default 9)")
    s.add_argument("--output", metavar="NAME", help="output to show (default: the first)")
    s.add_argument("--at", type=_assignment, action="append", default=[],
                   metavar="NAME=VALUE", help="fix an input (systems with > 2 inputs)")
    s.add_argument("--csv", action="store_true",
                   help="write every grid point as CSV (inputs, outputs) instead")
    s.set_defaults(func=cmd_surface)

    c = sub.add_parser("check", help="validate a rule file and summarise it")
    c.add_argument("file", metavar="FILE", help="rule file (.json or MATLAB .fis)")
    c.set_defaults(func=cmd_check)

    v = sub.add_parser("convert", help="convert between JSON and MATLAB .fis")
    v.add_argument("src", metavar="IN", help="source (.json or .fis)")
    v.add_argument("dst", metavar="OUT", help="destination (.json or .fis)")
    v.set_defaults(func=cmd_convert)


def _load(path):
    from fuzzynav.fuzzy import load_fis

    _kind(path)
    return load_fis(path)


def _kind(path) -> str:
    for ext in _FORMATS:
        if str(path).lower().endswith(ext):
            return ext
    raise FuzzynavError(f"{path}: unknown rule-file extension; use .json or .fis")


def _fmt(v: float) -> str:
    return f"{v:.6g}"


def _decimals(width: float) -> int:
    return int(min(8, max(0, 3 - math.floor(math.log10(width)))))


# ------------------------------------------------------------------------- surface
def _axes(fis, fixed: dict):
    for name in fixed:
        if name not in fis.input_names:
            raise FuzzynavError(f"--at {name}: no such input; inputs: "
                                f"{', '.join(fis.input_names)}")
    free = [v for v in fis.inputs if v.name not in fixed]
    if not free:
        raise FuzzynavError("--at fixes every input; leave one or two free")
    return free[:2], {v.name: fixed.get(v.name, 0.5 * sum(v.range))
                      for v in fis.inputs if v not in free[:2]}


def _surface_values(fis, axes, held, n):
    grids = [np.linspace(v.range[0], v.range[1], n) for v in axes]
    mesh = np.meshgrid(*grids, indexing="ij")
    inputs = {v.name: m for v, m in zip(axes, mesh)}
    inputs.update({k: np.full(mesh[0].shape, x) for k, x in held.items()})
    out, info = fis.evaluate(inputs, return_info=True)
    return grids, inputs, out, info


def cmd_surface(args) -> int:
    """Print the control surface (table, or CSV with ``--csv``)."""
    fis = _load(args.file)
    if args.output is not None and args.output not in fis.output_names:
        raise FuzzynavError(f"--output {args.output}: no such output; outputs: "
                            f"{', '.join(fis.output_names)}")
    axes, held = _axes(fis, dict(args.at))
    grids, inputs, out, info = _surface_values(fis, axes, held, args.grid)
    if args.csv:
        names = list(fis.input_names)
        outs = [args.output] if args.output else list(fis.output_names)
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(names + outs)
        flat = {k: np.asarray(v).ravel() for k, v in {**inputs, **out}.items()}
        for i in range(flat[outs[0]].size):
            w.writerow([repr(float(flat[k][i])) for k in names + outs])
        return 0
    name = args.output or fis.output_names[0]
    _print_surface(fis, name, axes, held, grids, out, info)
    return 0


def _print_header(fis, name, held, info):
    ops = fis.operators.as_dict()
    var = fis.output(name)
    print(f"{fis.name}  ({fis.type}: " + ", ".join(f"{k} {v}" for k, v in ops.items()) + ")")
    line = f"output {name} in [{_fmt(var.range[0])}, {_fmt(var.range[1])}], exact values"
    if held:
        line += "; held: " + ", ".join(f"{k}={_fmt(v)}" for k, v in held.items())
    print(line)
    if info.n_no_rule:
        print(f"({info.n_no_rule} grid points fire no rule: they show the default "
              f"{_fmt(var.default_value)})")


def _print_surface(fis, name, axes, held, grids, out, info):
    var = fis.output(name)
    dec = _decimals(var.range[1] - var.range[0])
    _print_header(fis, name, held, info)
    print()
    values = np.asarray(out[name])
    if len(axes) == 1:
        others = [o for o in fis.output_names if o != name]
        head = [axes[0].name, name] + others
        rows = [[_fmt(x), f"{values[i]:.{dec}f}"] + [f"{out[o][i]:.6g}" for o in others]
                for i, x in enumerate(grids[0])]
        _table(head, rows, left=1)
        return
    print(f"rows: {axes[0].name}    columns: {axes[1].name}")
    head = [""] + [_fmt(x) for x in grids[1]]
    rows = [[_fmt(x)] + [f"{v:.{dec}f}" for v in values[i]] for i, x in enumerate(grids[0])]
    _table(head, rows, left=1)


def _table(head, rows, left=1):
    widths = [max(len(str(r[j])) for r in [head] + rows) for j in range(len(head))]

    def line(cells):
        parts = [str(c).ljust(w) if j < left else str(c).rjust(w)
                 for j, (c, w) in enumerate(zip(cells, widths))]
        return "  ".join(parts).rstrip()

    print(line(head))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print(line(r))


# --------------------------------------------------------------------------- check
def _terms_text(v) -> str:
    return "  ".join(f"{t.name} {t.mf}(" + ", ".join(_fmt(p) for p in t.params) + ")"
                     for t in v.terms)


def _rules_summary(fis) -> str:
    weights = sorted({r.weight for r in fis.rules})
    conn = sorted({r.connective for r in fis.rules})
    w = "all weights 1" if weights == [1.0] else f"weights {_fmt(weights[0])}..{_fmt(weights[-1])}"
    return f"rules ({len(fis.rules)}): {w}; connective {'/'.join(conn)}"


def _binding(fis, path):
    """The rule file's parsed binding (None without one): a bad one fails the check."""
    if fis.binding is None:
        return None
    from fuzzynav.filters.adaptation.binding import Binding

    return Binding.of(fis, path)


def cmd_check(args) -> int:
    """Validate a rule file and print a one-screen summary."""
    from fuzzynav.fuzzy.lint import advisories

    fis = _load(args.file)
    binding = _binding(fis, args.file)
    print(f"{args.file}: OK ({_FORMATS[_kind(args.file)]}), {fis.type} system {fis.name!r}")
    print("operators: " + ", ".join(f"{k} {v}" for k, v in fis.operators.as_dict().items()))
    for title, variables in (("inputs", fis.inputs), ("outputs", fis.outputs)):
        print(f"{title} ({len(variables)}):")
        for v in variables:
            extra = f" default {_fmt(v.default)}" if v.default is not None else ""
            print(f"  {v.name} [{_fmt(v.range[0])}, {_fmt(v.range[1])}]{extra}: "
                  f"{_terms_text(v)}")
    print(_rules_summary(fis))
    table = rule_grid(fis)
    if table:
        _table(*table)
    if binding is not None:
        feeds = ", ".join(f"{b.name} <- {b.statistic}({b.channel})" for b in binding.inputs)
        print(f"binding: adapter {binding.adapter!r}, {feeds}, window {binding.window}"
              + (f", sensor {binding.sensor!r}" if binding.sensor else ""))
    if fis.provenance:
        src = fis.provenance.get("source") or fis.provenance.get("study") or "-"
        print(f"provenance: {src if len(src) <= 88 else src[:85] + '...'}")
    print("compiled kernel: " + ("yes" if fis.is_compilable else
                                 "no (curved output terms: adaptive quadrature in Python)"))
    notes = advisories(fis)
    print("advisories:" + (" none" if not notes else ""))
    for n in notes:
        print(f"  - {n}")
    return 0


# ------------------------------------------------------------------------- convert
def cmd_convert(args) -> int:
    """Convert a rule file between JSON and MATLAB .fis (by extension), atomically."""
    from fuzzynav.fuzzy.fis_matlab import dropped_fields
    from fuzzynav.fuzzy.io import save_fis

    fis = _load(args.src)
    kind = _kind(args.dst)
    save_fis(fis, args.dst)
    print(f"wrote {args.dst} ({_FORMATS[kind]})")
    if kind == ".fis" and dropped_fields(fis):
        print(f"note: .fis cannot hold {', '.join(dropped_fields(fis))}; not written",
              file=sys.stderr)
    return 0
