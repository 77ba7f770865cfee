"""The cold-start helper (fuzzynav.filters.precompile): its kernel list matches the kernels'
arguments, and the start/done/skip protocol shares the work both ways."""
from __future__ import annotations

import inspect
import subprocess
import sys

from fuzzynav.filters import precompile

#: a stand-in helper: reports kernel "a" compiled, then echoes what the parent writes
_FAKE = ("import sys; print('start a', flush=True); print('done a', flush=True); "
         "print('start c', flush=True); sys.stderr.write(sys.stdin.readline()); "
         "sys.stderr.flush()")


def test_every_kernel_has_a_signature_of_its_arity():
    sigs = precompile.signatures()
    assert set(sigs) == set(precompile.KERNELS)
    for name in precompile.KERNELS:
        disp = precompile.dispatcher(name)
        assert len(inspect.signature(disp.py_func).parameters) == len(sigs[name]), name
        assert disp.targetoptions.get("nopython", True), name


def test_claim_waits_for_done_and_hands_back_the_unstarted():
    proc = subprocess.Popen([sys.executable, "-c", _FAKE], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    helper = precompile.Helper(proc)
    while "c" not in helper.started:  # the helper has written its lines
        assert helper._read(30.0)
    assert helper.claim("a")  # done by the helper: load it from the cache
    assert not helper.claim("b")  # not started: this process compiles it, the helper skips
    err = proc.stderr.read().decode()
    assert err == "skip b\n"
    assert not helper.claim("c")  # started, but the helper ended without it
    assert helper.waited_s >= 0.0
    proc.stderr.close()
    helper.stop()
    assert proc.returncode is not None


def test_off_switch(monkeypatch):
    monkeypatch.setenv(precompile.ENV_SWITCH, "0")
    assert not precompile.enabled()
