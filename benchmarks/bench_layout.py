"""Core state offsets as compile-time constants or as an int array passed at run time.

The error-model kernel ``fill_F`` (the most index-heavy kernel of the loop) is compiled twice
from its own source: as shipped, where ``X_ATT``, ``X_VEL``, ``X_POS`` are module integers
that numba freezes into the machine code, and rewritten to read the same offsets from an
``int64`` array argument.  Both must give the same ``F``; the script reports the time per
call (best of several rounds, CPU time).  Usage: ``python benchmarks/bench_layout.py``.
"""
from __future__ import annotations

import argparse
import inspect
import re
import sys
import textwrap
import time
from pathlib import Path

import numba as nb
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav.filters import error_model  # noqa: E402
from fuzzynav.filters.layout import LAYOUT_15, X_ATT, X_POS, X_VEL  # noqa: E402
from fuzzynav.nav.strapdown import make_nav  # noqa: E402

# each named offset of fill_F's module, written in terms of the three core starts
_OFFSETS = {"X_ATT": "off[0]", "X_VEL": "off[1]", "X_POS": "off[2]",
            "_VE": "off[1]", "_VN": "(off[1] + 1)", "_VU": "(off[1] + 2)",
            "_LAT": "off[2]", "_LON": "(off[2] + 1)", "_HGT": "(off[2] + 2)",
            "_E": "off[2]", "_N": "(off[2] + 1)"}


def _array_variant(fn, name, space):
    """``fn`` recompiled with its core offsets read from an extra ``off`` argument."""
    src = textwrap.dedent(inspect.getsource(fn.py_func))
    src = re.sub(r"^@nb\.njit\(.*\)\n", "", src, flags=re.M)
    src = src.replace(f"def {fn.__name__}(", f"def {name}(off, ", 1)
    src = src.replace("_to_metric(", "_to_metric_arr(off, ")
    for const, expr in _OFFSETS.items():
        src = re.sub(rf"\b{const}\b", expr, src)
    exec(compile(src, f"<{name}>", "exec"), space)  # noqa: S102 (our own source)
    space[name] = nb.njit(space[name])
    return space[name]


def _fill_F_array_variant():
    space = dict(vars(error_model))
    _array_variant(error_model._to_metric, "_to_metric_arr", space)
    return _array_variant(error_model.fill_F, "fill_F_arr", space)


@nb.njit
def _calls_const(F, nav, C, f, s, k, t, reps):
    for _ in range(reps):
        error_model.fill_F(F, nav, C, f, s, k, t)


def _make_calls_array(fill):
    @nb.njit
    def calls(off, F, nav, C, f, s, k, t, reps):
        for _ in range(reps):
            fill(off, F, nav, C, f, s, k, t)
    return calls


def _best(fn, rounds=7):
    best = np.inf
    for _ in range(rounds):
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reps", type=int, default=200_000)
    ap.add_argument("--no-write", action="store_true", help="do not update docs/benchmarks.md")
    args = ap.parse_args(argv)
    n = LAYOUT_15.n
    nav = make_nav(np.array([0.66, 1.96, 825.0]), np.array([12.0, -3.0, 0.4]),
                   np.array([0.9, 0.1, -0.2, 0.37]) / np.linalg.norm([0.9, 0.1, -0.2, 0.37]))
    C = np.eye(3)
    f = np.array([0.3, -0.2, 9.81])
    s, k, t = error_model.ErrorModel().block_arrays()
    off = np.array([X_ATT, X_VEL, X_POS], dtype=np.int64)
    calls_arr = _make_calls_array(_fill_F_array_variant())
    F1, F2 = np.zeros((n, n)), np.zeros((n, n))
    _calls_const(F1, nav, C, f, s, k, t, 1)
    calls_arr(off, F2, nav, C, f, s, k, t, 1)
    assert np.array_equal(F1, F2), "the two variants disagree"
    t_c = _best(lambda: _calls_const(F1, nav, C, f, s, k, t, args.reps))
    t_a = _best(lambda: calls_arr(off, F2, nav, C, f, s, k, t, args.reps))
    per_call = 1e9 / args.reps
    lines = ["## Core offsets: compile-time constants or an index array "
             "(`benchmarks/bench_layout.py`)",
             "", f"`fill_F` of the 15-state layout, {args.reps:,} calls, best of 7 (CPU time). "
             f"Machine: {machine()}.", "",
             "| core offsets | ns per call |", "|---|---|",
             f"| module constants, frozen at compile time (shipped) | {t_c * per_call:.0f} |",
             f"| read from an int64 array argument | {t_a * per_call:.0f} |", "",
             "Both give the identical F. The loop uses constants for the core blocks (`att`, "
             "`vel`, `pos` always come first) and the int arrays of `StateLayout.block_arrays` "
             "for the sensor blocks, whose number and order vary per run."]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("layout", text)


if __name__ == "__main__":
    main()
