"""Command-line interface ``fuzzynav``.

Each command group lives in its own module with a ``register(subparsers)`` function;
add a module name to :data:`COMMAND_MODULES` to add commands.  Errors caused by user
input (:class:`fuzzynav.errors.FuzzynavError`) print one line and exit with code 2; a
filter run that diverged (non-finite metrics) prints one line and exits with code 3.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from fuzzynav.errors import FuzzynavError

#: modules under ``fuzzynav.cli`` that contribute sub-commands, in help order
COMMAND_MODULES = ("fis", "nav", "study")


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every registered command group."""
    from fuzzynav import __version__

    parser = argparse.ArgumentParser(
        prog="fuzzynav",
        description="Fuzzy adaptive Kalman filtering for integrated navigation.",
    )
    parser.add_argument("--version", action="version", version=f"fuzzynav {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"fuzzynav.cli.{name}").register(sub)
    return parser


def main(argv=None) -> int:
    """Entry point: parse ``argv`` and run the chosen command; return the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except FuzzynavError as exc:
        print(f"fuzzynav: error: {exc}", file=sys.stderr)
        return getattr(exc, "exit_code", 2)  # 3: a run diverged (RunDivergedError)
    except KeyboardInterrupt:  # pragma: no cover - interactive
        print("fuzzynav: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
