"""Project-level promises: CI runs the README's test command; docs exist for every page linked."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```\n(.*?)\n```", readme, re.S)
    test_cmd = [b for b in blocks if re.search(r"&& pytest( |$)", b.strip())]
    assert len(test_cmd) == 1
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert test_cmd[0].strip() in [line.strip() for line in ci]


def test_readme_links_resolve():
    readme = (ROOT / "README.md").read_text()
    for target in re.findall(r"\]\(([^)#]+)\)", readme):
        assert (ROOT / target).exists(), target


def test_numba_cache_is_keyed_by_the_sources(tmp_path):
    import numba

    import fuzzynav

    pkg = Path(fuzzynav.__file__).parent
    assert Path(numba.config.CACHE_DIR).name == fuzzynav.source_key(pkg, numba.__version__)
    (tmp_path / "a.py").write_text("x = 1\n")
    k1 = fuzzynav.source_key(tmp_path)
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    k2 = fuzzynav.source_key(tmp_path)
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")
    assert len({k1, k2, fuzzynav.source_key(tmp_path)}) == 3


def test_written_files_get_the_ordinary_mode(tmp_path):
    import os
    import stat

    from fuzzynav import plots
    from fuzzynav.fuzzy import load_fis, save_fis

    mask = os.umask(0o022)
    try:
        save_fis(load_fis(ROOT / "rules" / "paper002_ror.json"), tmp_path / "r.json")
        fig = plots.plt.figure()
        plots.save(fig, tmp_path / "f.png")
    finally:
        os.umask(mask)
    for name in ("r.json", "f.png"):
        mode = stat.S_IMODE((tmp_path / name).stat().st_mode)
        assert mode & 0o044, f"{name} is not readable by others: {oct(mode)}"
