"""tools/line_census.py: the line kinds of a source and the same-shape function finder."""
import importlib.util
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parent.parent / "tools" / "line_census.py"
_spec = importlib.util.spec_from_file_location("line_census", _PATH)
lc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(lc)

SOURCE = '''"""Module docstring,
over two lines."""
import math

__all__ = ["area",
           "Box"]


# a comment alone
def area(r):
    """One line."""
    s = "# not a comment"  # a trailing comment: still code
    return math.pi * r * r


class Box:
    """A box.

    With a paragraph.
    """

    side = 1.0
'''


def test_every_line_is_counted_once_by_its_kind():
    c = lc.census(SOURCE)
    assert c == {"code": 8, "docstring": 7, "comment": 1, "blank": 6, "all": 2}
    assert sum(c[k] for k in lc.KINDS) == len(SOURCE.splitlines())


def test_a_hash_inside_a_string_is_not_a_comment_line():
    c = lc.census('x = """\n# inside the string\n"""\n')
    assert c["comment"] == 0 and c["code"] == 3


COPIES = {
    "a.py": '''
def mean_of(values, scale):
    """Docstrings differ and do not count."""
    total = 0.0
    for v in values:
        total += v * scale
    return total / len(values)
''',
    "b.py": '''
def average(xs, k):
    acc = 1.0
    for x in xs:
        acc += x * k
    return acc / len(xs)


def other(xs, k):
    acc = 0.0
    for x in xs:
        acc -= x * k
    return acc / len(xs)
''',
}


def test_renamed_copies_are_found_and_a_different_body_is_not():
    found = lc.copies(COPIES, min_lines=4)
    assert len(found) == 1
    saved, group = found[0]
    assert [where for _, where in group] == ["a.py:2:mean_of", "b.py:2:average"]
    assert saved == 5  # the smaller copy (average, 5 lines) goes; mean_of (6) stays


def test_functions_shorter_than_the_threshold_are_left_out():
    assert lc.copies(COPIES, min_lines=7) == []


def test_folder_totals_add_up_the_files(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(SOURCE)
    (tmp_path / "pkg" / "n.py").write_text("x = 1\n\n")
    out = lc.totals(lc.sources_at(None, ["pkg"], tmp_path), ["pkg"])["pkg"]
    assert out["files"] == 2
    assert out["lines"] == len(SOURCE.splitlines()) + 2
    assert out["code"] == 9 and out["blank"] == 7


def test_a_source_that_does_not_parse_is_an_error():
    with pytest.raises(SyntaxError):
        lc.census("def broken(:\n")
