"""Bounded text reading, shared by the rule-file formats (writing: ``fuzzynav.fileio``)."""
from __future__ import annotations

import os
from pathlib import Path

from fuzzynav.errors import DataMissingError
from fuzzynav.fuzzy._where import FisError

__all__ = ["MAX_FILE_BYTES", "read_text"]

#: larger files are refused before parsing
MAX_FILE_BYTES = 8 * 1024 * 1024


def read_text(path, what: str = "rule file") -> str:
    """Read a UTF-8 text file of at most :data:`MAX_FILE_BYTES` bytes."""
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_FILE_BYTES:
                raise FisError(p, "", f"file is {size} bytes; a {what} may be at most "
                                      f"{MAX_FILE_BYTES} bytes")
            data = fh.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise DataMissingError(f"{p}: no such {what}") from None
    except IsADirectoryError:
        raise FisError(p, "", f"is a directory, not a {what}") from None
    except PermissionError:
        raise FisError(p, "", "permission denied") from None
    if len(data) > MAX_FILE_BYTES:
        raise FisError(p, "", f"a {what} may be at most {MAX_FILE_BYTES} bytes")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FisError(p, "", f"not UTF-8 text (byte {exc.start})") from None
