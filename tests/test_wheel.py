"""A non-editable install ships the rule files the named filters use (``fuzzynav/rules``).

The fast test builds the package (``setup.py build_py``, the step that copies ``rules/``)
into a temporary directory and loads the ``fakf`` default rules from that copy alone, from a
directory outside the checkout.  The slow test (run by ``.ci/run``) builds the wheel,
installs it into a fresh virtual environment and runs ``fuzzynav run paper000 --filter
fakf`` there.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("fuzzynav", "rules", "pyproject.toml", "setup.py", "MANIFEST.in", "README.md")


def _clean_env(**extra) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("FUZZYNAV_RULES", "PYTHONPATH", "PYTHONSAFEPATH")}
    env.update(PYTHONWARNINGS="ignore", **extra)
    return env


def _copy_sources(dest: Path) -> Path:
    """The files a build reads, copied (a build writes build/ and egg-info into its tree)."""
    for name in SOURCES:
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns(
                "__pycache__", "*.nbi", "*.nbc", "*.egg-info"))
        else:
            shutil.copy2(src, dest / name)
    return dest


CHECK = """
from pathlib import Path
import fuzzynav
from fuzzynav.filters.catalog import PAPER000_RULES, find_rule_file
from fuzzynav.fuzzy import load_fis
for name in PAPER000_RULES:
    path = find_rule_file(name)
    assert Path(fuzzynav.__file__).parent / "rules" / name == path, path
    load_fis(path)
print("ok", Path(fuzzynav.__file__).parent)
"""


def test_the_built_package_carries_the_named_filters_rules(tmp_path):
    src = _copy_sources(tmp_path / "src")
    lib = tmp_path / "lib"
    subprocess.run([sys.executable, "setup.py", "-q", "build_py", "--build-lib", str(lib)],
                   cwd=src, check=True, capture_output=True, env=_clean_env())
    shipped = sorted(p.name for p in (lib / "fuzzynav" / "rules").glob("*.json"))
    assert shipped == sorted(p.name for p in (ROOT / "rules").glob("*.json"))
    assert (lib / "fuzzynav" / "realdata" / "datasets.json").is_file()  # fuzzynav data fetch
    # every paper folder's scenario files ship (fuzzynav scenarios lists them from there)
    built = sorted(p.relative_to(lib) for p in (lib / "fuzzynav" / "papers").rglob("*.toml"))
    assert built == sorted(p.relative_to(ROOT) for p in (ROOT / "fuzzynav" / "papers").rglob(
        "scenarios/*.toml")) and len(built) >= 30
    elsewhere = tmp_path / "elsewhere"  # no rules/ here, and not the checkout
    elsewhere.mkdir()
    # (no JIT: importing the filters would compile their kernels for this new path; only
    # files are looked up here)
    out = subprocess.run([sys.executable, "-c", CHECK], cwd=elsewhere, capture_output=True,
                         text=True, env=_clean_env(PYTHONPATH=str(lib), NUMBA_DISABLE_JIT="1"))
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"ok {lib / 'fuzzynav'}"


@pytest.mark.slow
def test_a_wheel_in_a_fresh_venv_runs_fakf_outside_the_checkout(tmp_path):
    src = _copy_sources(tmp_path / "src")
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-q",
                    "-w", str(wheels)], check=True, capture_output=True, env=_clean_env())
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()"
                           "['purelib'])"], capture_output=True, text=True, check=True)
    # the dependencies come from this environment (a plain path: its .pth files, among them
    # the editable install of the checkout, are not processed)
    Path(site.stdout.strip(), "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps",
                    "--no-index", "-q", *map(str, wheels.glob("*.whl"))], check=True,
                   capture_output=True, env=_clean_env())
    work = tmp_path / "work"
    work.mkdir()
    out = subprocess.run([str(venv / "bin" / "fuzzynav"), "run", "paper000", "--filter", "fakf",
                          "--mc", "1", "--cache", str(tmp_path / "cache")], cwd=work,
                         capture_output=True, text=True,
                         env=_clean_env(NUMBA_CACHE_DIR=str(tmp_path / "numba")))
    assert out.returncode == 0, out.stderr
    assert "fakf" in out.stdout
    where = subprocess.run([str(py), "-c", "import fuzzynav; print(fuzzynav.__file__)"],
                           cwd=work, capture_output=True, text=True, env=_clean_env())
    assert where.stdout.startswith(str(venv)), where.stdout
