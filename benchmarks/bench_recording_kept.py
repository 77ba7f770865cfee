"""What a run on a car recording read from its file keeps per IMU line.

Two synthetic drives (``tests/realdata/rtklib_files.write_drive``, the rest and turns, then
a straight cruise of 200 s and of 1 400 s: 26 k and 146 k lines of 100-Hz IMU) are loaded
``streamed=True`` and run through the validation protocol (``ekf``, chunks of 3 000
samples, 1-Hz output) once to compile, then again under tracemalloc; the difference of
what the two runs keep (their outcomes: fixes, errors at the reference epochs, kept rows)
divided by the difference in lines is the growth per line; the event logs the outcomes
hold are counted apart.  Quoted in docs/data.md ("Memory").

Usage: ``python benchmarks/bench_recording_kept.py`` (about a minute); prints only.
"""
from __future__ import annotations

import sys
import tempfile
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fuzzynav.realdata.loaders.rtklib import load_rtklib  # noqa: E402
from fuzzynav.realdata.validate import validate  # noqa: E402
from fuzzynav.sim.segments import Segment  # noqa: E402
from tests.realdata.rtklib_files import DRIVE_SEGMENTS, write_drive  # noqa: E402

FIELDS = ("time_s", "residual", "S_diag", "nis", "flag", "diag")


def kept(cruise_s: float) -> tuple:
    """(IMU lines, bytes kept after the run, event-log bytes held) of one drive."""
    with tempfile.TemporaryDirectory() as d:
        write_drive(Path(d), segments=list(DRIVE_SEGMENTS) + [Segment("cruise", cruise_s)])
        rec = load_rtklib(Path(d), mounting=None, streamed=True)
        kw = dict(chunk_samples=3000, output_rate_hz=1.0)
        validate(rec, "ekf", **kw)
        tracemalloc.start()
        v = validate(rec, "ekf", **kw)
        cur = tracemalloc.get_traced_memory()[0]
        tracemalloc.stop()
        events = sum(getattr(e, f).nbytes for r in v.runs.values()
                     for e in r.result.events.values() for f in FIELDS)
        return rec.imu.n_samples, cur, events


def main() -> int:
    (a, ka, ea), (b, kb, eb) = kept(200.0), kept(1400.0)
    print(f"lines {a} and {b}: kept {(kb - ka) / (b - a):.1f} B a line after both feeds' "
          f"runs, of it event logs {(eb - ea) / (b - a):.1f} B")
    return 0


if __name__ == "__main__":
    sys.exit(main())
