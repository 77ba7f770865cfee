"""Every malformed scenario file and study config of the corpus gives one clear CLI error.

Each file goes through ``fuzzynav.cli.main`` in-process: exit code 2, exactly one line on
stderr naming the file, the key at fault and the phrase of ``expected.json``, no traceback.
Size bombs (runs of 10^11 samples, 10^15 turns, 10^8 cloud spells) must be refused from
their sample counts, before anything is allocated: their peak of traced Python/numpy
memory stays below a few megabytes, where running them would need terabytes.
"""
import json
import tracemalloc
from pathlib import Path

import pytest

from fuzzynav.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"
SCENARIOS = DATA / "bad_scenarios"
STUDIES = DATA / "bad_studies"
EXPECTED_SCENARIOS = json.loads((SCENARIOS / "expected.json").read_text())
EXPECTED_STUDIES = json.loads((STUDIES / "expected.json").read_text())
#: files whose sample or window counts would exhaust memory if they were simulated
SIZE_BOMBS = {"imu_rate_bomb.toml", "year_long_static.toml", "s_turns_bomb.toml",
              "outage_spells_tiny_period.toml", "cloud_spells_tiny.toml"}
#: a refused file may allocate this much while being parsed and checked (a run of the
#: smallest bomb would need ~1e5 times more)
PEAK_LIMIT_BYTES = 32 * 2**20


def _argv(kind, path, cache):
    if kind == "scenario":
        return ["run", str(path), "--cache", str(cache)]
    return ["study", "run", str(path), "--cache", str(cache), "--no-summary"]


def _check_one_line_error(capsys, argv, name, expected):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("fuzzynav: error: "), err
    assert "Traceback" not in err and out == ""
    assert name in err
    if expected["where"]:  # "" for a whole-file problem (not TOML, empty, too deep)
        assert f": {expected['where']}: " in err
    assert expected["contains"] in err
    return err


def test_corpora_are_complete_and_large_enough():
    for corpus, expected, least in ((SCENARIOS, EXPECTED_SCENARIOS, 30),
                                    (STUDIES, EXPECTED_STUDIES, 15)):
        files = {p.name for p in corpus.iterdir() if p.name != "expected.json"}
        assert files == set(expected)
        assert len(files) >= least
    assert SIZE_BOMBS <= set(EXPECTED_SCENARIOS)


@pytest.mark.parametrize("name", sorted(EXPECTED_SCENARIOS))
def test_bad_scenario_gives_one_clear_error(capsys, tmp_path, name):
    _check_one_line_error(capsys, _argv("scenario", SCENARIOS / name, tmp_path), name,
                          EXPECTED_SCENARIOS[name])
    assert not any(tmp_path.iterdir())  # nothing was simulated or cached


@pytest.mark.parametrize("name", sorted(EXPECTED_STUDIES))
def test_bad_study_config_gives_one_clear_error(capsys, tmp_path, name):
    _check_one_line_error(capsys, _argv("study", STUDIES / name, tmp_path), name,
                          EXPECTED_STUDIES[name])
    assert not list(STUDIES.glob("*.journal"))  # no study was created


@pytest.fixture(scope="module")
def warm_cli(tmp_path_factory):
    """Run the command once so that its imports are not counted as the bombs' memory."""
    cache = tmp_path_factory.mktemp("warm")
    main(_argv("scenario", SCENARIOS / "nan_rate.toml", cache))
    main(_argv("study", STUDIES / "nan_weight.toml", cache))


@pytest.mark.parametrize("kind, path", [("scenario", SCENARIOS / n) for n in sorted(SIZE_BOMBS)]
                         + [("study", STUDIES / "scenario_size_bomb.toml")],
                         ids=lambda x: getattr(x, "name", x))
def test_size_bombs_are_refused_before_allocating(capsys, tmp_path, warm_cli, kind, path):
    capsys.readouterr()
    tracemalloc.start()
    try:
        code = main(_argv(kind, path, tmp_path))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert peak < PEAK_LIMIT_BYTES, f"peak {peak} B while refusing {path.name}"
