"""Command-line interface ``fuzzynav``.

Each command group lives in its own module with a ``register(subparsers)`` function;
add a module name to :data:`COMMAND_MODULES` to add commands.  Errors caused by user
input (:class:`fuzzynav.errors.FuzzynavError`) print one line and exit with code 2; a
filter run that diverged (non-finite metrics) prints one line and exits with code 3.
Output that cannot be written to stdout (a full disk) is one line and code 2; a reader
that closed the pipe (``| head``) ends the command quietly with code 141 (128 + SIGPIPE,
what the shell reports for a program killed by it).
"""
from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys

from fuzzynav.errors import MAX_MESSAGE, FuzzynavError, OutputError, bounded

#: modules under ``fuzzynav.cli`` that contribute sub-commands, in help order
COMMAND_MODULES = ("fis", "nav", "study", "data", "docs")


#: exit code when the reader of stdout went away (128 + SIGPIPE, as the shell reports it)
EXIT_BROKEN_PIPE = 141


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


class StdoutError(OutputError):
    """Writing to stdout failed (``broken_pipe``: the reader closed it)."""

    def __init__(self, exc: OSError):
        super().__init__("<stdout>", exc, "output")
        # "nothing was changed" would be wrong: part of the output may have gone out
        self.args = (f"stdout: cannot write the output: {self.reason}",)
        self.broken_pipe = exc.errno == errno.EPIPE


class _GuardedStdout:
    """``stdout`` whose write failures are :class:`StdoutError`: every command's output
    (``print``, ``csv.writer``) goes through here, so no command needs its own handling."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except OSError as exc:
            raise StdoutError(exc) from None

    def flush(self):
        try:
            self._stream.flush()
        except OSError as exc:
            raise StdoutError(exc) from None

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _silence_stdout() -> None:
    """Point stdout's file descriptor at the null device: the output still buffered would
    otherwise fail again when the interpreter flushes it at exit (a second message)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (tests capture it)
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def one_line(message: str) -> str:
    """``message`` on one line and at most :data:`MAX_MESSAGE` characters."""
    return bounded(" ".join(str(message).splitlines()))


def main(argv=None) -> int:
    """Entry point: parse ``argv`` and run the chosen command; return the exit code.

    Called as the command (``argv`` None: ``sys.argv``), a command that compiles numba
    kernels says so in one line on stderr (:mod:`fuzzynav.compile_notice`); called with
    ``argv`` (tests, scripts reading the output) it does not.
    """
    if argv is None:
        from fuzzynav import compile_notice

        compile_notice.install()
    parser = build_parser()
    stdout = sys.stdout
    sys.stdout = _GuardedStdout(stdout)
    try:
        try:
            args = parser.parse_args(argv)
        except SystemExit:
            # --help and --version print, then exit: their output is guarded like any other
            sys.stdout.flush()
            raise
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # a full disk shows here, not as a warning at exit
        return code
    except StdoutError as exc:
        sys.stdout = stdout
        _silence_stdout()
        if exc.broken_pipe:
            return EXIT_BROKEN_PIPE
        print(f"fuzzynav: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except FuzzynavError as exc:
        print(f"fuzzynav: error: {one_line(exc)}", file=sys.stderr)
        return getattr(exc, "exit_code", 2)  # 3: a run diverged (RunDivergedError)
    except KeyboardInterrupt:  # pragma: no cover - interactive
        print("fuzzynav: interrupted", file=sys.stderr)
        return 130
    finally:
        sys.stdout = stdout


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
