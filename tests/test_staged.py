"""A writer killed inside :func:`fuzzynav.fileio.staged` leaves its staging directory; the
next writer into the same place removes it, and leaves live writers' directories alone."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import textwrap

from fuzzynav.fileio import staged, sweep_staged

_KILLED_WRITER = textwrap.dedent("""
    import os, signal, sys
    from fuzzynav.fileio import staged
    with staged(sys.argv[1]) as tmp:
        (tmp / "report.md").write_text("half a report")
        os.kill(os.getpid(), signal.SIGKILL)
""")


def _leftovers(directory):
    return sorted(p.name for p in directory.glob(".staged-*"))


def test_a_killed_writers_directory_is_removed_by_the_next(tmp_path):
    proc = subprocess.run([sys.executable, "-c", _KILLED_WRITER, str(tmp_path)], timeout=60)
    assert proc.returncode == -signal.SIGKILL
    left = _leftovers(tmp_path)
    assert len(left) == 1 and not (tmp_path / "report.md").exists()
    with staged(tmp_path) as tmp:
        (tmp / "report.md").write_text("a whole report")
    assert _leftovers(tmp_path) == []
    assert (tmp_path / "report.md").read_text() == "a whole report"


def test_live_and_foreign_writers_are_left_alone(tmp_path):
    host = socket.gethostname()
    mine = tmp_path / f".staged-{os.getpid()}@{host}-abc123"
    other_host = tmp_path / f".staged-1@not-{host}-abc123"
    unnamed = tmp_path / ".staged-k2j3h4"  # an older fuzzynav's: owner unknown
    for d in (mine, other_host, unnamed):
        d.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, timeout=60)
    gone = tmp_path / f".staged-{int(dead.stdout)}@{host}-xyz789"
    gone.mkdir()
    (gone / "half.md").write_text("x")
    assert sweep_staged(tmp_path) == [gone]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        d.name for d in (mine, other_host, unnamed))
