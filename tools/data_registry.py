"""Maintainer script: rebuild ``fuzzynav/realdata/datasets.json`` (what ``fuzzynav data
fetch`` downloads) from local copies of the public recordings.

``python tools/data_registry.py DATASETS_DIR`` reads every file listed in
:data:`LAYOUT` under ``DATASETS_DIR`` (the maintainers' ``../shared/datasets``, whose files
are byte-identical to the public ones), computes its SHA-256 and size, and writes the
registry: per dataset its files with the path inside the dataset directory, the URL path
(relative to the raw-file host, ``https://raw.githubusercontent.com/``) and the hash.
The URLs name fixed commits, so the hashes can never change under a user.  After a rebuild
check one file by hand against the host (``curl -sL URL | sha256sum``).

Upstream layouts (checked against the two repositories):

* A-KIT (``ansfl/A-KIT``): ``Data/TrajectoryN/{IMU,DVL,GT}_trajectoryN.csv``; the files at
  commit :data:`AKIT_COMMIT` are our top-level ones, the DVL and GT files as republished
  at :data:`AKIT_CORRECTED_COMMIT` ("corrected the transformation") our ``corrected/``.
* The car drive (``rtklibexplorer/GNSS_IMU``): ``data/drive_0708/`` at
  :data:`DRIVE_COMMIT`, and the repository's ``LICENSE`` (BSD-3-Clause) beside the data.
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "fuzzynav" / "realdata" / "datasets.json"

AKIT_REPO = "ansfl/A-KIT"
AKIT_COMMIT = "c2168ede00642f37019f4e856050f30b08d8de06"
AKIT_CORRECTED_COMMIT = "0c4fca0c00727a0bf9a343d2af3101200ac9aeaa"
DRIVE_REPO = "rtklibexplorer/GNSS_IMU"
DRIVE_COMMIT = "8235ee6c5f349db529bf43ad556a3769b346b5a1"
AKIT_TRAJECTORIES = range(1, 9)


def _akit_files() -> list:
    """(path in the dataset, URL path) of the A-KIT files."""
    out = []
    for n in AKIT_TRAJECTORIES:
        up = f"Data/Trajectory{n}"
        for stream in ("IMU", "DVL", "GT"):
            name = f"{stream}_trajectory{n}.csv"
            out.append((name, f"{AKIT_REPO}/{AKIT_COMMIT}/{up}/{name}"))
        for stream in ("DVL", "GT"):
            name = f"{stream}_trajectory{n}.csv"
            out.append((f"corrected/{name}", f"{AKIT_REPO}/{AKIT_CORRECTED_COMMIT}/{up}/{name}"))
    return out


def _drive_files() -> list:
    """(path in the dataset, URL path) of the car drive's files."""
    base = f"{DRIVE_REPO}/{DRIVE_COMMIT}"
    names = ("imu_1934.csv", "imu_1934.csv.tag", "gnss_1934_sf.pos")
    return [(n, f"{base}/data/drive_0708/{n}") for n in names] + [("LICENSE", f"{base}/LICENSE")]


#: dataset name -> (recording kind, description, source, licence, files)
LAYOUT = {
    "akit": ("akit",
             ("A-KIT AUV: INS (100 Hz), DVL and post-processed reference, trajectories 1-8 "
              "(Cohen & Klein, EAAI 146 (2025) 110221: cite it)"),
             f"https://github.com/{AKIT_REPO}",
             "no licence file: validate with it, do not redistribute",
             _akit_files()),
    "rtklib-drive": ("rtklib",
                     ("car drive, Boulder 2025-07-08, 549 s: consumer MEMS IMU (100 Hz) + "
                      "RTK GNSS (4 Hz), RTKLIB formats"),
                     f"https://github.com/{DRIVE_REPO}",
                     "BSD-3-Clause (LICENSE beside the data)",
                     _drive_files()),
}


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file, read in 1-MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def build(datasets_dir: Path) -> dict:
    """The registry document for the copies under ``datasets_dir``."""
    doc = {"format": 1, "datasets": {}}
    for name, (kind, description, source, licence, files) in LAYOUT.items():
        entries = []
        for rel, url in files:
            path = datasets_dir / name / rel
            entries.append({"path": rel, "url": url, "sha256": sha256_of(path),
                            "size_bytes": path.stat().st_size})
        doc["datasets"][name] = {"kind": kind, "description": description, "source": source,
                                 "licence": licence, "files": entries}
    return doc


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    doc = build(Path(argv[0]))
    fd, tmp = tempfile.mkstemp(dir=OUT.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    os.replace(tmp, OUT)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
