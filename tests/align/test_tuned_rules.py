"""Regression of tuned alignment rule files: each ``rules/*.json`` whose ``expected`` block
says ``kind = "alignment"`` is re-run on its scenario and seed and must reproduce its
metrics; the exporter itself (``fuzzynav study run`` of an alignment study) is run on a tiny
study so this test never only skips."""
import json
from pathlib import Path

import pytest

from fuzzynav.align import alignment_run as R
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.align.tune import Runs
from fuzzynav.cli import main
from fuzzynav.fuzzy import load_fis

ROOT = Path(__file__).resolve().parents[2]
RTOL = 1e-6


def alignment_rule_files():
    out = []
    for path in sorted((ROOT / "rules").glob("*.json")):
        doc = json.loads(path.read_text(encoding="utf-8"))
        if doc.get("expected", {}).get("kind") == "alignment":
            out.append(path)
    return out


def check(path):
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    exp = doc["expected"]
    scn = load_alignment_scenario(exp["scenario"])
    log = R.simulate(scn, int(exp["seed"]))
    ep = R.epochs(scn, log, int(exp["seed"]))
    out = R.run_align_filter(exp["filter"], scn, log, ep, rules=load_fis(path))
    got = R.metrics(out, scn.threshold_arcmin)
    assert exp["metrics"]
    for key, value in exp["metrics"].items():
        assert got[key] == pytest.approx(value, rel=RTOL, abs=1e-9), (Path(path).name, key)


@pytest.mark.parametrize("path", alignment_rule_files(), ids=lambda p: p.name)
def test_tuned_alignment_rules_reproduce_their_expected_metrics(path):
    check(path)


SHORT = """kind = "alignment"
base = "paper002-rmismatch"
name = "short"
duration_s = 80.0
[imu]
rate_hz = 10.0
"""


def test_the_tuner_exports_a_rule_file_that_reproduces_itself(tmp_path, capsys):
    scn = tmp_path / "short.toml"
    scn.write_text(SHORT)
    cfg = tmp_path / "tune.toml"
    cfg.write_text(f'''template = "{ROOT / 'rules' / 'paper002_ror.json'}"
output = "tuned.json"
n_trials = 2
train = ["{scn}"]
train_seeds = [0]
test = []
expected_scenario = "{scn}"
expected_seed = 3
''')
    assert main(["study", "run", str(cfg)]) == 0
    out = capsys.readouterr().out
    assert out.rstrip().endswith(f"wrote {tmp_path / 'tuned.json'}")
    summary = json.loads(out[:out.rindex("wrote ")])
    # the exported file scores what the study reported for its best trial
    rescored, _ = Runs([(str(scn), 0)]).score(load_fis(tmp_path / "tuned.json"),
                                              "align-fuzzy", 1.0)
    assert rescored == pytest.approx(summary["train"]["tuned"], rel=1e-9)
    doc = json.loads((tmp_path / "tuned.json").read_text())
    assert doc["expected"]["kind"] == "alignment" and doc["provenance"]["trials"] == 2
    assert doc["binding"]["window"] == summary["best_params"]["window"]
    check(tmp_path / "tuned.json")
