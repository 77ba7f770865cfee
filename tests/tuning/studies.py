"""Tiny study configurations for the tuning tests (written as TOML into a temp directory)."""
from __future__ import annotations

import copy
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RULES = ROOT / "rules"
STUDIES = ROOT / "studies"
TINY = Path(__file__).resolve().parent / "data" / "tiny.toml"
GPS = RULES / "paper000_gps_sins.json"
ATT = RULES / "paper000_attitude.json"
ROR_GNSS = RULES / "paper002_ror_gnss.json"

#: one controller (the paper's GPS/SINS alpha), two training runs, one test run
BASE = {
    "name": "tiny",
    "study": {"sampler": "random", "seed": 0, "trials": 4, "pruner": "none",
              "stale_after_s": 30.0},
    "train": {"scenarios": [str(TINY)], "seeds": [0, 1]},
    "test": {"scenarios": [str(TINY)], "seeds": [100], "compare": ["ekf", "fakf"]},
    "controllers": [{"name": "gps", "template": str(GPS),
                     "partitions": {"dom_pos": [3, 5], "dom_vel": [3, 5], "alpha": [3, 4]},
                     "window": [5, 30], "output_range": [1.01, 1.3]}],
}

ATT_CONTROLLER = {"name": "att", "template": str(ATT), "partitions": {"dom_att": [3, 5]},
                  "window": [5, 30], "output_range": [1.01, 1.3]}


_INLINE = ("partitions", "weights")  # tables written inline


def _value(v) -> str:
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return json.dumps(v)  # str, int, float, bool: TOML spells them the same way


def to_toml(doc: dict, prefix: str = "") -> str:
    """A small TOML writer: scalars, arrays, inline tables, tables, arrays of tables."""
    scalars, tables, arrays = [], [], []
    for k, v in doc.items():
        if isinstance(v, dict) and k not in _INLINE:
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            scalars.append(f"{k} = {_value(v)}")
    out = "\n".join(scalars) + "\n"
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        out += f"\n[{name}]\n" + to_toml(v, name)
    for k, items in arrays:
        name = f"{prefix}.{k}" if prefix else k
        for item in items:
            out += f"\n[[{name}]]\n" + "\n".join(f"{a} = {_value(b)}" for a, b in item.items()) \
                + "\n"
    return out


def study_doc(**changes) -> dict:
    """:data:`BASE` with changes: ``study={...}`` merges into a table, others replace."""
    doc = copy.deepcopy(BASE)
    for k, v in changes.items():
        if isinstance(v, dict) and isinstance(doc.get(k), dict):
            doc[k].update(v)
        else:
            doc[k] = v
    return doc


def write_study(directory, doc=None, file_name=None, **changes) -> Path:
    """Write a study config (``doc``, or :data:`BASE` with ``changes``); its path."""
    doc = doc if doc is not None else study_doc(**changes)
    path = Path(directory) / (file_name or f"{doc.get('name', 'study')}.toml")
    path.write_text(to_toml(doc), encoding="utf-8")
    return path


def finished_study(directory, cache_dir, trials=4, **changes):
    """Run a tiny study to ``trials`` in ``directory``: ``(config, study)``."""
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.study_run import run_study

    cfg = load_study_config(write_study(directory, **changes))
    return cfg, run_study(cfg, trials=trials, cache_dir=cache_dir, progress=False)
