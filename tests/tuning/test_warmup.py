"""The first study run on a cold kernel cache says it is compiling, with a live count, before
the trials start; a warm cache prints nothing and compiles nothing here."""
from __future__ import annotations

import io

import numba
import pytest

from fuzzynav import compile_notice
from fuzzynav.tuning import warmup


@pytest.fixture
def fake_compile(tmp_path, monkeypatch):
    """A keyed cache in tmp_path; "compiling" writes two index files into it."""
    cache = tmp_path / "numba" / "key"
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache))
    monkeypatch.delenv("FUZZYNAV_NUMBA_CACHE", raising=False)
    calls = []

    def compile_(cfg, cache_dir):
        calls.append(cache_dir)
        sub = cache / "fuzzynav_filters"
        sub.mkdir(parents=True, exist_ok=True)
        for name in ("loop.run_loop-10.py311.nbi", "kalman.gain-20.py311.nbi"):
            (sub / name).write_bytes(b"")

    monkeypatch.setattr(warmup, "compile_by_running", compile_)
    return cache, calls


def test_a_cold_cache_is_compiled_here_under_a_message(fake_compile, monkeypatch, capsys):
    """The command's one notice (fuzzynav.compile_notice) comes before the compiling, once,
    to stderr that is not a terminal (no live count there)."""
    cache, calls = fake_compile
    said = io.StringIO()
    monkeypatch.setattr(compile_notice, "_INSTALLED", compile_notice.CompileNotice(said))
    assert compile_notice.cache_is_cold()
    assert warmup.warm_up(cfg=None, cache_dir="sim") is True
    assert said.getvalue() == compile_notice.COLD_TEXT + "\n"
    assert capsys.readouterr().err == ""  # no progress bar off a terminal
    assert calls == ["sim"] and not compile_notice.cache_is_cold()
    # warm now: nothing compiled, nothing said
    assert warmup.warm_up(cfg=None, cache_dir="sim") is False
    assert calls == ["sim"] and capsys.readouterr().err == ""
    assert said.getvalue() == compile_notice.COLD_TEXT + "\n"


def test_no_keyed_cache_no_warm_up(fake_compile, monkeypatch, capsys):
    monkeypatch.setenv("FUZZYNAV_NUMBA_CACHE", "0")  # numba's own per-file caches
    assert warmup.warm_up(cfg=None) is False
    assert fake_compile[1] == [] and capsys.readouterr().err == ""
