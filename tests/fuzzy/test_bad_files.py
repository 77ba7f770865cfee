"""Each malformed file of the corpus gives one clear error naming the file and the path."""
import json
from pathlib import Path

import pytest

from fuzzynav.errors import DataMissingError, FuzzynavError
from fuzzynav.fuzzy import FisError, load_fis
from fuzzynav.fuzzy.io import MAX_FILE_BYTES

CORPUS = Path(__file__).resolve().parents[1] / "data" / "bad_fis"
EXPECTED = json.loads((CORPUS / "expected.json").read_text())


def test_corpus_is_complete():
    files = {p.name for p in CORPUS.iterdir() if p.name != "expected.json"}
    assert files == set(EXPECTED)
    assert len(files) >= 25


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_file_gives_one_clear_error(name):
    path = CORPUS / name
    with pytest.raises(FisError) as exc:
        load_fis(path)
    err = exc.value
    message = str(err)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    assert err.where == EXPECTED[name]["where"]
    assert EXPECTED[name]["contains"] in err.what
    assert isinstance(err, FuzzynavError)


def test_huge_file_is_refused_before_parsing(tmp_path):
    path = tmp_path / "huge.json"
    with open(path, "wb") as fh:
        fh.truncate(MAX_FILE_BYTES + 1)  # sparse: nothing is really written
    with pytest.raises(FisError, match=f"{path}: file is {MAX_FILE_BYTES + 1} bytes"):
        load_fis(path)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(DataMissingError, match="no such rule file"):
        load_fis(tmp_path / "absent.json")
    with pytest.raises(FisError, match="is a directory"):
        load_fis(tmp_path)


def test_nothing_is_executed_from_a_file(tmp_path):
    # names that look like code are rejected as names, never evaluated
    doc = json.loads((CORPUS / "unknown_version.json").read_text())
    doc["version"] = 1
    doc["inputs"][0]["terms"][0]["name"] = "__import__('os').system('touch PWNED')"
    path = tmp_path / "evil.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(FisError, match="does not match"):
        load_fis(path)
    assert not (tmp_path / "PWNED").exists() and not Path("PWNED").exists()
