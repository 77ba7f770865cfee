"""Error messages stay one readable line however large the offending value is."""
import json
from pathlib import Path

import pytest

from fuzzynav.fuzzy import FisError, load_fis
from fuzzynav.errors import MAX_QUOTE
from fuzzynav.fuzzy.io import MAX_FILE_BYTES
from tests.fuzzy.systems import ROR


def _doc_with_rules(n: int) -> dict:
    doc = json.loads(Path(ROR).read_text())
    rule = doc["rules"][0]
    doc["rules"] = [rule] * n
    return doc


def test_a_schema_error_on_140000_rules_is_a_short_message(tmp_path):
    path = tmp_path / "huge.json"
    text = json.dumps(_doc_with_rules(140_000), separators=(",", ":"))
    assert len(text) < MAX_FILE_BYTES  # refused by the schema, not by the size limit
    path.write_text(text)
    with pytest.raises(FisError) as info:
        load_fis(path)
    msg = str(info.value)
    assert len(msg) < 2 * MAX_QUOTE + 200 and "\n" not in msg
    assert msg.startswith(f"{path}: $.rules: ")
    assert "140000 items; at most 100000" in msg


@pytest.mark.parametrize("where", ["range", "name", "rules[0].then"])
def test_long_values_are_quoted_briefly(where):
    """jsonschema quotes the whole offending value in its messages."""
    doc = json.loads(Path(ROR).read_text())
    big = {f"k{i}": i for i in range(5000)}
    if where == "range":  # a wrong type
        doc["inputs"][0]["range"] = big
    elif where == "name":  # too long
        doc["inputs"][0]["name"] = "x" * 50_000
    else:
        doc["rules"][0]["then"] = list(big)
    with pytest.raises(FisError) as info:
        load_fis(doc)
    msg = str(info.value)
    assert len(msg) < 2 * MAX_QUOTE + 200
    assert f"$.{where}" in msg or f"$.inputs[0].{where}" in msg
    assert "..." in msg  # cut, and says so
