"""``--json --plot DIR``: stdout stays one JSON document; the notices of the written figures
go to stderr (before, ``wrote PATH`` lines followed the JSON on stdout and broke every
reader of it).  Recordings: ``tests/realdata/test_rtklib_cli.py``."""
import json
from pathlib import Path

import pytest

from fuzzynav.cli import main

TINY = Path(__file__).resolve().parents[1] / "tuning" / "data" / "tiny.toml"


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("argv", [
    ("run", TINY, "--filter", "fakf"),
    ("compare", TINY, "--filters", "ekf,fakf"),
    ("run", "paper000-nominal", "--filter", "fakf", "--align", "align-kf"),
], ids=["run", "compare", "run-align"])
def test_json_with_figures_is_one_json_document(capsys, tmp_path, sim_cache, argv):
    code, out, err = _run(capsys, *argv, "--json", "--plot", tmp_path, "--cache", sim_cache)
    assert code == 0, err
    doc = json.loads(out)                       # nothing but the document on stdout
    assert doc["filters"] and "wrote" not in out
    written = [Path(line.split(" ", 1)[1]) for line in err.splitlines()
               if line.startswith("wrote ")]
    assert written and all(p.parent == tmp_path and p.stat().st_size > 0 for p in written)
    code, out, _ = _run(capsys, *argv, "--plot", tmp_path, "--cache", sim_cache)
    assert code == 0 and "wrote " in out        # without --json the notices stay on stdout
