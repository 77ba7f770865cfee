"""Exceptions that carry one clear, user-facing line.

Every error a user can cause with bad input (a file, a field, a value) is raised as a
:class:`FuzzynavError` subclass whose message names the file, the field (a JSON path or
a TOML key) and what was wrong.  The CLI prints that one line and exits with code 2.
"""
from __future__ import annotations

__all__ = ["MAX_MESSAGE", "MAX_QUOTE", "brief", "bounded", "FuzzynavError", "InputFileError",
           "UnknownNameError", "DataMissingError", "OutputError", "RunDivergedError",
           "OutputRateError"]


#: longest message a fuzzynav error carries (characters); a longer one is cut and says by
#: how much, so a library caller (a notebook, a study worker's log) gets a readable line too
MAX_MESSAGE = 1000

#: longest quotation of an offending value in a message (characters)
MAX_QUOTE = 200


def brief(value) -> str:
    """``repr(value)``, cut to :data:`MAX_QUOTE` characters and then saying what it was
    (a 200 000-character name in a message would bury what was wrong with it)."""
    text = repr(value)
    if len(text) <= MAX_QUOTE:
        return text
    what = type(value).__name__
    for kind, unit in ((list, "items"), (dict, "keys"), (str, "characters")):
        if isinstance(value, kind):
            what = f"{kind.__name__} of {len(value)} {unit}"
    return f"{text[:MAX_QUOTE]}... ({what})"


def bounded(text: str) -> str:
    """``text`` cut to :data:`MAX_MESSAGE` characters, saying how many were cut."""
    if len(text) <= MAX_MESSAGE:
        return text
    return f"{text[:MAX_MESSAGE]}… ({len(text) - MAX_MESSAGE} characters cut)"


class FuzzynavError(Exception):
    """Base class of errors caused by user input (exit code 2 in the CLI).

    A message longer than :data:`MAX_MESSAGE` is cut here, once, whoever raises it.
    """

    def __init__(self, *args):
        super().__init__(*(bounded(a) if isinstance(a, str) else a for a in args))


class InputFileError(FuzzynavError, ValueError):
    """A file (rule file, scenario, study config, recording) is malformed.

    Parameters
    ----------
    path : str or os.PathLike or None
        The file at fault (``None`` for an in-memory document).
    where : str
        The field at fault, e.g. a JSON path ``$.inputs[0].terms[1].params``.
    what : str
        What was wrong with it.
    """

    def __init__(self, path, where: str, what: str):
        self.path = None if path is None else str(path)
        self.where = where
        self.what = what
        prefix = f"{self.path}: " if self.path else ""
        loc = f"{where}: " if where else ""
        super().__init__(f"{prefix}{loc}{what}")


class UnknownNameError(FuzzynavError, KeyError):
    """A name (scenario, filter, adapter, sensor) is not registered."""

    def __init__(self, kind: str, name: str, known):
        self.kind, self.name = kind, name
        self.known = sorted(known)
        super().__init__(f"unknown {kind} {brief(name)}; known: {', '.join(self.known)}")

    def __str__(self) -> str:  # KeyError would quote the message
        return self.args[0]


class DataMissingError(FuzzynavError, FileNotFoundError):
    """A recording or data file the user named is not there."""


class OutputError(FuzzynavError):
    """A file could not be written (read-only place, full disk, a file where a directory
    should be, a name too long).

    Raised after the temporary file is removed: the file at ``path``, if there was one, is
    as it was, and so is every other file unless ``written`` names it.

    Parameters
    ----------
    path : str or os.PathLike
        The file (or directory) that was to be written.
    reason : OSError or str
        What the system said.
    what : str, optional
        What the file is ("simulation cache", "figure"); named in the message.
    written : list of str or os.PathLike, optional
        Files already moved into place when a group of files failed part-way (see
        :func:`fuzzynav.fileio.publish_all`): the message lists them instead of saying
        that nothing was changed.
    """

    def __init__(self, path, reason, what: str = "", written=()):
        self.path = str(path)
        if isinstance(reason, OSError) and reason.strerror:
            reason = reason.strerror
        self.reason = str(reason)
        self.what = what
        self.written = [str(p) for p in written]
        thing = f"the {what}" if what else "it"
        changed = (f"files written before it: {', '.join(self.written)}" if self.written
                   else "nothing was changed")
        super().__init__(f"{self.path}: cannot write {thing}: {self.reason} ({changed})")

    def __str__(self) -> str:
        return self.args[0]


class OutputRateError(FuzzynavError):
    """A requested output rate a run cannot keep, worded for the command line
    (``--output-rate``); a study re-words it for its ``[streaming]`` key.

    Parameters
    ----------
    reason : str
        Why it cannot be kept.
    rate_hz : float, optional
        The requested rate [Hz], when the message should name it.
    """

    def __init__(self, reason: str, rate_hz: float | None = None):
        self.reason = reason
        self.rate_hz = None if rate_hz is None else float(rate_hz)
        rate = "" if rate_hz is None else f" {self.rate_hz:g} Hz"
        super().__init__(f"--output-rate{rate}: {reason}")


class RunDivergedError(FuzzynavError):
    """A filter run gave non-finite metrics: no table is printed, the CLI exits with
    :attr:`exit_code` (3, to tell a diverged run from bad input, which exits with 2)."""

    exit_code = 3
