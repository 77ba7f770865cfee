"""Library callers get the bounded one-line messages the CLI prints.

The CLI cuts long messages itself; a notebook or a study worker calling the library gets
the exception directly, so the cap must hold in the exception (one place: the base class).
"""
import pytest

from fuzzynav.errors import (MAX_MESSAGE, MAX_QUOTE, DataMissingError, FuzzynavError,
                             InputFileError, UnknownNameError)
from fuzzynav.realdata.sources import parse_data_spec
from fuzzynav.filters.named import FILTERS

LONG = 200_000


def test_an_unknown_name_is_quoted_briefly():
    with pytest.raises(UnknownNameError) as exc:
        FILTERS.lookup("s" * LONG)
    msg = str(exc.value)
    assert len(msg) < MAX_QUOTE + 2_000 and "str of 200000 characters" in msg
    assert "ekf, " in msg  # the known names are still listed
    assert exc.value.name == "s" * LONG  # the attribute keeps the whole name


def test_a_missing_recording_directory_names_itself_briefly(tmp_path):
    with pytest.raises(DataMissingError) as exc:
        parse_data_spec(f"rtklib:{tmp_path / ('d' * LONG)}")
    msg = str(exc.value)
    assert len(msg) <= MAX_MESSAGE + 40 and f"({LONG + len(str(tmp_path)) * 2}" not in msg
    assert msg.startswith(str(tmp_path)) and msg.endswith("characters cut)")
    assert isinstance(exc.value, FileNotFoundError)  # still an OSError for callers


@pytest.mark.parametrize("cls, args", [(FuzzynavError, ("x" * LONG,)),
                                       (DataMissingError, ("x" * LONG,)),
                                       (InputFileError, ("f.json", "$.a", "x" * LONG))])
def test_every_error_is_cut_once_in_the_base_class(cls, args):
    msg = str(cls(*args))
    cut = len(msg) - MAX_MESSAGE
    assert 0 < cut < 40 and "characters cut" in msg


def test_a_short_message_is_untouched():
    assert str(FuzzynavError("f.json: $.a: bad")) == "f.json: $.a: bad"
