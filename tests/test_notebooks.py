"""The notebooks in ``notebooks/`` run end to end, offline, without writing into the checkout.

Each notebook is copied into a temporary working directory and executed there by nbclient
(a real Jupyter kernel, the one of this Python), failing on the first cell error.  The
notebooks contain their own checks (``assert`` cells: round trips, hand-computed values,
exported metrics reproduced), so "runs without error" means those hold too.

What "does not write into the repository" is checked against: the kernel's ``TMPDIR`` is a
directory of the test, which must be empty again after the kernel stops (the notebooks
keep their files in a ``TemporaryDirectory``); the working directory must hold only the
notebook; and the parts of the checkout that the notebooks read from (``rules/``,
``studies/``, ``notebooks/``, the top level) must have the same files with the same
contents. The whole tree is not watched because other work may add files to it meanwhile.

Real recordings (paper 004's A-KIT part) reach the kernel as ``$FUZZYNAV_DATA`` (the
directory the other tests use, :func:`tests.conftest.datasets_dir`); a notebook skips such
a part with a message when they are absent, and when they are present the test checks that
the part really ran.
"""
from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

from tests.conftest import datasets_dir

REPO = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))
EXPECTED = ["01_fuzzy_system.ipynb", "02_paper000.ipynb", "03_study.ipynb",
            "04_paper001.ipynb", "05_paper002.ipynb", "06_paper003.ipynb", "07_paper004.ipynb",
            "08_own_filter.ipynb"]
#: per cell; generous because a cold numba cache compiles the filter loop (a minute or more
#: on a loaded 2-core machine) in the first cell that runs a filter
CELL_TIMEOUT_S = 600
#: committed notebooks are small: outputs cleared, no embedded figures
MAX_BYTES = 40_000
WATCHED = ("rules", "studies", "notebooks")
#: notebooks with a part on real recordings: name -> (recording file under the datasets
#: directory, what the notebook prints when it ran that part); the directory reaches the
#: kernel as ``$FUZZYNAV_DATA`` and, when the recording is there, the part must have run
REAL_DATA = {"07_paper004.ipynb": ("akit/IMU_trajectory1.csv", "A-KIT: ran on trajectories")}


def _ids(path: Path) -> str:
    return path.stem


def _fingerprint() -> dict:
    """Relative path -> SHA-256 of every file the notebooks could plausibly write to."""
    files = [p for p in REPO.iterdir() if p.is_file()]
    for name in WATCHED:
        files += [p for p in (REPO / name).rglob("*") if p.is_file()
                  and "__pycache__" not in p.parts and ".ipynb_checkpoints" not in p.parts]
    return {str(p.relative_to(REPO)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in files}


def test_the_expected_notebooks_are_there():
    assert [p.name for p in NOTEBOOKS] == EXPECTED


@pytest.mark.parametrize("path", NOTEBOOKS, ids=_ids)
def test_committed_with_outputs_cleared(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code, "a notebook without code"
    for i, cell in enumerate(code):
        assert cell.outputs == [] and cell.execution_count is None, \
            f"{path.name}: code cell {i} was committed with outputs"
    assert path.stat().st_size < MAX_BYTES
    # the "why" for the reader: every notebook opens with a markdown cell
    assert nb.cells[0].cell_type == "markdown"


@pytest.fixture(scope="module")
def shared_sim_cache(tmp_path_factory):
    """One simulation cache for the notebooks (02 and 03 share paper000 logs)."""
    return tmp_path_factory.mktemp("nb-sim-cache")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=_ids)
def test_notebook_runs(path, tmp_path, shared_sim_cache, monkeypatch):
    work = tmp_path / "work"
    kernel_tmp = tmp_path / "kernel-tmp"
    work.mkdir()
    kernel_tmp.mkdir()
    shutil.copy(path, work / path.name)
    monkeypatch.setenv("FUZZYNAV_CACHE", str(shared_sim_cache))
    monkeypatch.setenv("TMPDIR", str(kernel_tmp))
    monkeypatch.delenv("FUZZYNAV_RULES", raising=False)
    data = datasets_dir().resolve()
    needs = REAL_DATA.get(path.name)
    have_data = needs is not None and (data / needs[0]).is_file()
    monkeypatch.setenv("FUZZYNAV_DATA", str(data))
    before = _fingerprint()

    nb = nbformat.read(work / path.name, as_version=4)
    client = NotebookClient(nb, timeout=CELL_TIMEOUT_S, kernel_name="python3",
                            resources={"metadata": {"path": str(work)}})
    client.execute()  # raises CellExecutionError on the first failing cell

    code = [c for c in nb.cells if c.cell_type == "code"]
    assert all(c.execution_count for c in code), "some code cells did not run"
    assert sorted(p.name for p in work.iterdir()) == [path.name]
    assert list(kernel_tmp.iterdir()) == [], "temporary files left behind"
    after = _fingerprint()
    assert after == before, "the notebook changed the checkout: " + ", ".join(
        sorted(k for k in after.keys() | before.keys() if after.get(k) != before.get(k)))
    figures = sum("image/png" in o.get("data", {}) for c in code for o in c.outputs)
    assert figures >= 2, "the figures did not reach the notebook (matplotlib backend?)"
    if have_data:
        printed = "".join(o.get("text", "") for c in code for o in c.outputs)
        assert needs[1] in printed, f"{path.name} skipped its real-data part, but {data} has it"
