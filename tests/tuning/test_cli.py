"""``fuzzynav study run | export | report`` on a tiny config: output, files, exit codes, and
one-line errors with exit code 2."""
from __future__ import annotations

import json

import pytest

from fuzzynav.cli import main
from fuzzynav.fuzzy import load_fis
from tests.tuning.studies import write_study


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_run_export_report(capsys, tmp_path, sim_cache):
    cfg = write_study(tmp_path)
    code, out, _ = run(capsys, "study", "run", cfg, "--trials", 3, "--cache", sim_cache)
    assert code == 0
    assert f"study tiny: 3 trials in journal:{tmp_path / 'tiny.journal'}" in out
    assert "best trial" in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("tuned", "fakf"))]
    assert sorted((r[0], r[1]) for r in rows) == [("fakf", "test"), ("fakf", "train"),
                                                   ("tuned", "test"), ("tuned", "train")]
    # resuming to a larger total continues the same study
    code, out, _ = run(capsys, "study", "run", cfg, "--trials", 4, "--no-summary",
                       "--cache", sim_cache)
    assert code == 0 and "4 trials" in out and "best trial" not in out

    target = tmp_path / "rules" / "mine.json"
    code, out, _ = run(capsys, "study", "export", cfg, "--out", target, "--cache", sim_cache)
    assert code == 0 and out.strip() == f"wrote {target}"
    assert load_fis(target).provenance["study"] == "tiny"
    code, out, _ = run(capsys, "study", "export", cfg, "--out", tmp_path / "t1.json",
                       "--trial", 1, "--cache", sim_cache)
    assert code == 0 and json.loads((tmp_path / "t1.json").read_text())["provenance"][
        "trial"] == 1

    code, out, _ = run(capsys, "study", "report", cfg, "--no-eval", "--cache", sim_cache)
    report = tmp_path / "tiny_report" / "report.md"
    assert code == 0 and f"wrote {report}" in out and report.is_file()
    assert f"optuna-dashboard {tmp_path / 'tiny.journal'}" in out


def test_another_storage_url(capsys, tmp_path, sim_cache):
    cfg = write_study(tmp_path)
    other = tmp_path / "elsewhere" / "s.journal"
    code, out, _ = run(capsys, "study", "run", cfg, "--trials", 2, "--no-summary",
                       "--storage", f"journal:{other}", "--cache", sim_cache)
    assert code == 0 and other.is_file() and not (tmp_path / "tiny.journal").exists()
    code, _, err = run(capsys, "study", "export", cfg, "--out", tmp_path / "x.json",
                       "--cache", sim_cache)
    assert code == 2 and "no study named 'tiny'" in err  # not in the default storage
    code, _, _ = run(capsys, "study", "export", cfg, "--out", tmp_path / "x.json",
                     "--storage", f"journal:{other}", "--cache", sim_cache)
    assert code == 0


def _error(capsys, *argv):
    code, out, err = run(capsys, *argv)
    lines = err.strip().splitlines()
    assert code == 2, (out, err)
    assert len(lines) == 1 and lines[0].startswith("fuzzynav: error: "), err
    return lines[0][len("fuzzynav: error: "):]


def test_one_line_errors(capsys, tmp_path, sim_cache):
    missing = tmp_path / "none.toml"
    assert _error(capsys, "study", "run", missing) == f"{missing}: study file not found"
    bad = write_study(tmp_path, study={"samplr": "tpe"}, file_name="bad.toml")
    assert _error(capsys, "study", "run", bad).startswith(f"{bad}: study.samplr: unknown key")
    cfg = write_study(tmp_path)
    msg = _error(capsys, "study", "export", cfg, "--out", tmp_path / "o.json")
    assert msg.startswith("no study named 'tiny'") and msg.endswith("run it first")
    assert not (tmp_path / "tiny.journal").exists()  # asking created nothing
    assert "no study named" in _error(capsys, "study", "report", cfg)
    assert "--workers must be >= 1" in _error(capsys, "study", "run", cfg, "--workers", 0)
    run(capsys, "study", "run", cfg, "--trials", 1, "--no-summary", "--cache", sim_cache)
    assert "has no trial 7" in _error(capsys, "study", "export", cfg, "--out",
                                      tmp_path / "o.json", "--trial", 7, "--cache", sim_cache)
    assert "must be a .json rule file" in _error(capsys, "study", "export", cfg, "--out",
                                                 tmp_path / "o.txt", "--cache", sim_cache)


def test_help_lists_the_actions(capsys):
    with pytest.raises(SystemExit) as ex:
        main(["study", "--help"])
    assert ex.value.code == 0
    out = capsys.readouterr().out
    assert all(a in out for a in ("run", "export", "report"))
