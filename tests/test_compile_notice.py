"""A command that compiles numba kernels says so once on stderr; one that compiles nothing
says nothing (fuzzynav.compile_notice, installed by the ``fuzzynav`` command)."""
from __future__ import annotations

import io
import os
import subprocess
import sys

import numba
import pytest
from numba.core import event

from fuzzynav import compile_notice


def _compile_event():
    """What numba does around a compilation (Dispatcher.compile): one "numba:compile"."""
    with event.trigger_event("numba:compile", data={"dispatcher": None, "args": ()}):
        pass


@pytest.fixture
def notice(monkeypatch):
    """A notice writing to a buffer, heard by numba for the test only."""
    out = io.StringIO()
    note = compile_notice.CompileNotice(out, cold=True)
    listener = compile_notice._listener(note)
    event.register("numba:compile", listener)
    yield note, out
    event.unregister("numba:compile", listener)


def test_one_line_for_many_compilations(notice):
    note, out = notice
    assert out.getvalue() == ""  # nothing compiled, nothing said
    for _ in range(3):
        _compile_event()
    assert out.getvalue() == compile_notice.COLD_TEXT + "\n"
    assert note.announce() is False  # a command's own announce after numba's: still one


def test_a_real_compilation_is_heard(notice):
    _, out = notice

    @numba.njit  # a new function: not in any cache, compiled here (~0.1 s)
    def add_two(a):
        return a + 2

    assert add_two(1) == 3 and add_two(1.5) == 3.5  # two signatures, two compilations
    assert out.getvalue().count("compiling numba kernels") == 1


def test_cold_means_no_compiled_kernel_in_the_keyed_cache(tmp_path, monkeypatch):
    monkeypatch.delenv("FUZZYNAV_NUMBA_CACHE", raising=False)
    cache = tmp_path / "key"
    assert compile_notice.cache_is_cold(cache)  # missing
    (cache / "fuzzynav_filters").mkdir(parents=True)
    assert compile_notice.cache_is_cold(cache)  # empty
    (cache / "fuzzynav_filters" / "loop.run_loop-150.py311.nbi").write_bytes(b"")
    assert not compile_notice.cache_is_cold(cache)
    assert compile_notice.notice_text(True) != compile_notice.notice_text(False)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache))
    assert compile_notice.kernel_cache() == cache
    monkeypatch.setenv("FUZZYNAV_NUMBA_CACHE", "0")  # numba's per-file caches: not judged
    assert compile_notice.kernel_cache() is None and not compile_notice.cache_is_cold()


def _command(args, cache_dir):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    env.pop("FUZZYNAV_NUMBA_CACHE", None)
    code = "import sys; from fuzzynav.cli import main; sys.exit(main())"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          env=env, timeout=900)


@pytest.mark.slow
def test_a_cold_run_says_it_compiles_once_and_a_warm_one_not(tmp_path):
    """The real command on an empty cache directory (a cold run: tens of seconds), then
    again on the cache it filled; stderr is a pipe, not a terminal."""
    args = ["run", "paper000", "--filter", "ekf", "--cache", str(tmp_path / "sim")]
    cold = _command(args, tmp_path / "numba")
    assert cold.returncode == 0, cold.stderr
    assert cold.stderr.splitlines().count(compile_notice.COLD_TEXT) == 1, cold.stderr
    assert "compiling" not in cold.stdout
    warm = _command(args, tmp_path / "numba")
    assert warm.returncode == 0 and "compiling" not in warm.stderr, warm.stderr
    assert warm.stdout == cold.stdout  # same results from the cached kernels
