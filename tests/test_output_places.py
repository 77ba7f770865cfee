"""Where fuzzynav writes: never a system directory; a study file's paths inside its directory.

The tests run as root, whom no permission stops, so ``/etc`` would really be written: the
refusals are checked before anything is created (and the targets checked afterwards).
"""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from fuzzynav.cli import main
from fuzzynav.errors import InputFileError, OutputError
from fuzzynav.fileio import check_place, is_inside, make_dir, staged, study_output, write_atomic
from fuzzynav.fuzzy import load_fis, save_fis, write_matlab_fis
from tests.tuning.test_baselines import TINY

ROOT = Path(__file__).resolve().parents[1]
TARGET = "/etc/fuzzynav-test-must-not-exist"
GPS_RULES = ROOT / "rules" / "paper000_gps_sins.json"


@pytest.fixture(autouse=True)
def _nothing_in_etc():
    assert not os.path.exists(TARGET) and not os.path.exists(f"{TARGET}.fis")
    yield
    for path in (TARGET, f"{TARGET}.fis"):
        assert not os.path.exists(path), f"{path} was written"


@pytest.mark.parametrize("writer", [
    lambda: make_dir(TARGET),
    lambda: write_atomic(f"{TARGET}/x.json", lambda tmp: Path(tmp).write_text("{}")),
    lambda: staged(TARGET).__enter__(),
    lambda: check_place("/usr/../etc/passwd-copy"),
    lambda: save_fis(load_fis(GPS_RULES), f"{TARGET}/x.json"),
    lambda: write_matlab_fis(load_fis(GPS_RULES), f"{TARGET}.fis"),
])
def test_no_writer_writes_into_a_system_directory(writer):
    with pytest.raises(OutputError, match="/etc is a system directory"):
        writer()


def test_tmp_and_home_are_fine(tmp_path):
    assert check_place(tmp_path / "out") == tmp_path / "out"
    assert is_inside(tmp_path / "a" / ".." / "b", tmp_path)
    assert not is_inside(tmp_path / ".." / "elsewhere", tmp_path)


@pytest.mark.parametrize("text", ["/etc/x.json", "../../../../tmp/x.json", "../x.json",
                                  "sub/../../x.json"])
def test_a_study_files_output_outside_its_directory_is_refused(tmp_path, text):
    study = tmp_path / "s" / "b.toml"
    study.parent.mkdir()
    with pytest.raises(InputFileError, match=r"baselines\.out: .* lies outside the study's"):
        study_output(text, study, "baselines.out")


def test_a_study_files_output_inside_its_directory_is_fine(tmp_path):
    study = tmp_path / "b.toml"
    assert study_output("out/tuned.json", study, "k") == tmp_path / "out" / "tuned.json"
    assert study_output(tmp_path / "x.json", study, "k") == tmp_path / "x.json"


def test_a_symlink_out_of_the_study_directory_is_refused(tmp_path):
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "escape").symlink_to("/etc")
    with pytest.raises(InputFileError, match="outside"):
        study_output("escape/x.json", tmp_path / "s" / "b.toml", "baselines.out")


def _baseline_study(out: str, storage: str) -> str:
    """The baseline tests' tiny study, writing to ``out`` with the ``[study]`` line
    ``storage`` (may be empty)."""
    text = TINY.format(tune='["huber-tuned"]').replace('out = "tuned.json"', f'out = "{out}"')
    return text.replace("[study]\n", f"[study]\n{storage}\n")


@pytest.mark.parametrize("out, storage, key", [
    (f"{TARGET}/tuned.json", "", "baselines.out"),
    ("../../../../tmp/fuzzynav-escape.json", "", "baselines.out"),
    ("tuned.json", f'storage = "journal:{TARGET}/b.journal"', "study.storage"),
])
def test_study_run_refuses_before_writing(tmp_path, capsys, out, storage, key):
    cfg = tmp_path / "b.toml"
    cfg.write_text(_baseline_study(out, storage))
    code = main(["study", "run", str(cfg), "--cache", str(tmp_path / "cache"), "--no-summary"])
    _, err = capsys.readouterr()
    assert code == 2 and f"{key}: " in err and "outside the study's directory" in err, err
    assert not Path("/tmp/fuzzynav-escape.json").exists()


def test_a_cli_cache_in_a_system_directory_is_one_line(tmp_path, capsys):
    code = main(["run", "paper000-steps", "--filter", "ekf", "--cache", TARGET])
    _, err = capsys.readouterr()
    assert code == 2 and "/etc is a system directory" in err and err.count("\n") == 1


@pytest.mark.parametrize("dst", [f"{TARGET}.fis", f"{TARGET}/x.json"])
def test_fis_convert_into_a_system_directory_is_one_line(capsys, dst):
    code = main(["fis", "convert", str(GPS_RULES), dst])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1, (out, err)
    assert "/etc is a system directory" in err and "rule file" in err


def test_fis_convert_writes_a_rule_file_with_the_usual_mode(tmp_path, capsys):
    dst = tmp_path / "new" / "gps.fis"
    assert main(["fis", "convert", str(GPS_RULES), str(dst)]) == 0
    assert dst.is_file() and load_fis(dst).output_names == load_fis(GPS_RULES).output_names
    mask = os.umask(0)
    os.umask(mask)
    assert dst.stat().st_mode & 0o777 == 0o666 & ~mask
    assert [p.name for p in dst.parent.iterdir()] == ["gps.fis"]  # no temporary file left
