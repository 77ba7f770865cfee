"""Publishing files written through a temporary file: the one place for atomic writes.

``tempfile.mkstemp`` creates files readable by their owner only (mode 0600); a rule file, a
figure or a cache file should get the usual mode (0666 minus the umask) like any file the
user writes.  :func:`publish` sets that mode and moves the temporary file into place.
"""
from __future__ import annotations

import os


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: mode of a newly written file: 0666 minus the process umask (read once, at import)
FILE_MODE = 0o666 & ~_umask()


def publish(tmp, path) -> None:
    """Give ``tmp`` the ordinary file mode and ``os.replace`` it onto ``path``."""
    os.chmod(tmp, FILE_MODE)
    os.replace(tmp, path)
