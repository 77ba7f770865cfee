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


def test_the_files_the_readme_commands_read_exist():
    """Every .toml / .json a README command reads (not one it writes with --out) is in the
    repository: ``ship-day.toml`` was named by three commands and shipped nowhere."""
    readme = (ROOT / "README.md").read_text()
    blocks = "\n".join(re.findall(r"```\n(.*?)\n```", readme, re.S))
    written, missing = set(), []
    for m in re.finditer(r"(--out\s+)?\b([\w./-]+\.(?:toml|json))\b", blocks):
        if m.group(1):  # written by the command (and read by the ones after it)
            written.add(m.group(2))
        elif m.group(2) not in written and not any(
                (d / m.group(2)).is_file() for d in (ROOT, ROOT / "studies")):
            missing.append(m.group(2))
    assert "examples/ship-day.toml" in blocks
    assert not missing, missing


def test_the_example_day_at_sea_is_a_day_long(tmp_path):
    from fuzzynav.sim.scenario import load_scenario

    s = load_scenario(ROOT / "examples" / "ship-day.toml")
    assert s.duration_s == 86400.0 and {"log", "pol"} <= set(s.sensors)


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
