"""The documentation site (mkdocs.yml): every public module has an API page, the site builds
strictly (a broken link, anchor or cross-reference fails) without writing into the checkout,
and the two local helpers in docsite/ (lists as GitHub reads them, Sphinx roles as links) do
what they say.  The tests that need the ``docs`` extra skip without it (it is in ``dev``)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "fuzzynav"


def _public_top_level() -> set[str]:
    """Subpackages and modules directly under fuzzynav/ without a leading underscore."""
    names = {p.stem for p in PKG.glob("*.py")}
    names |= {p.name for p in PKG.iterdir() if (p / "__init__.py").is_file()}
    return {n for n in names if not n.startswith("_")}


def _need_docs_extra() -> None:
    # only mkdocs itself: with mkdocs there, a missing theme or plugin fails the build loudly
    pytest.importorskip("mkdocs", reason="mkdocs missing: pip install -e '.[docs]'")


def _mkdocs_build(config: Path, site_dir: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")  # Material's end-of-life banner
    # no -q: mkdocs 1.6 then drops the warnings before --strict counts them (exit 0)
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict",
         "-f", str(config), "-d", str(site_dir)],
        cwd=config.parent, env=env, capture_output=True, text=True, timeout=300)


def test_every_public_module_has_an_api_page_in_the_nav():
    config = (ROOT / "mkdocs.yml").read_text()
    pages = {p.stem for p in (ROOT / "docs" / "api").glob("*.md")} - {"index"}
    missing, stale = _public_top_level() - pages, pages - _public_top_level()
    assert not missing, (f"add docs/api/NAME.md holding '::: fuzzynav.NAME' and a nav entry "
                         f"'fuzzynav.NAME: api/NAME.md' in mkdocs.yml for {sorted(missing)}")
    assert not stale, f"docs/api pages of modules that are gone: {sorted(stale)}"
    for name in pages:
        text = (ROOT / "docs" / "api" / f"{name}.md").read_text()
        assert f"::: fuzzynav.{name}\n" in text, name
        assert f"api/{name}.md" in config, f"docs/api/{name}.md is not in the nav"


def test_site_builds_strictly_outside_the_checkout(tmp_path):
    _need_docs_extra()

    def listing():  # the checkout's top level and docs/ (other tests may add to the rest)
        return ({p.name for p in ROOT.iterdir()} & {"site", ".cache"},
                sorted((ROOT / "docs").rglob("*")))

    before = listing()
    res = _mkdocs_build(ROOT / "mkdocs.yml", tmp_path / "site")
    assert res.returncode == 0, res.stdout + res.stderr
    assert listing() == before  # nothing written into the checkout
    site = tmp_path / "site"
    home = (site / "index.html").read_text()
    # the README is the home page, its docs/... links rewritten to the site's pages
    assert "Fuzzy adaptive Kalman filtering" in home
    assert 'href="paper000/"' in home and 'href="docs/' not in home
    # the API is rendered from the docstrings: a function, a `#:`-documented constant
    # and a numpydoc parameter table
    fuzzy = (site / "api" / "fuzzy" / "index.html").read_text()
    assert 'id="fuzzynav.fuzzy.io.load_fis"' in fuzzy and "Parameters" in fuzzy
    assert 'id="fuzzynav.units.DPH"' in (site / "api" / "units" / "index.html").read_text()
    assert not list(site.rglob("*.py"))  # no package source copied onto the site
    # the guide pages' `fuzzynav.x.y` code spans link into the API reference (63 when written)
    guide = [p for p in site.glob("*/index.html") if p.parent.name != "api"]
    links = sum(p.read_text().count('href="../api/') for p in guide)
    assert links >= 30, links
    assert not any("<autoref" in p.read_text() for p in guide)  # every one resolved or not


BROKEN = {  # each kind of broken reference, and what the warning must name
    "[a rule file](../rules/paper000_gps_sins.json)": "rules/paper000_gps_sins.json",
    "[no such page](missing.md)": "missing.md",
    "[no such section](#no-such-heading)": "#no-such-heading",
    "[load][fuzzynav.fuzzy.io.no_such_function]": "fuzzynav.fuzzy.io.no_such_function",
    "::: stale": "Parameter 'gain' does not appear in the function signature",
    "(stale role)": ":func:`stale.gone` names no object of the package",
}
STALE_DOCSTRING = '''def scale(x):
    """Scale x, as :func:`stale.gone` did.

    Parameters
    ----------
    gain : float
        A parameter that was renamed in the signature but not here.
    """
'''


def test_the_strict_build_refuses_every_kind_of_broken_reference(tmp_path):
    """The site's own settings, on a one-page site, warn on each one and so fail (a numpydoc
    docstring out of step with its signature included)."""
    _need_docs_extra()
    import yaml

    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    config["nav"] = [{"Home": "index.md"}]
    config["docs_dir"] = "docs"
    config["hooks"] = [str(ROOT / hook) for hook in config.get("hooks", [])]
    (plugin,) = [p["mkdocstrings"] for p in config["plugins"] if "mkdocstrings" in p]
    python = plugin["handlers"]["python"]
    python["paths"] = [str(ROOT), str(tmp_path)]
    python["options"]["extensions"] = [  # the local ones by their path in the checkout
        str(ROOT / ext) if ".py" in ext else ext for ext in python["options"]["extensions"]]
    (tmp_path / "stale.py").write_text(STALE_DOCSTRING)
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# Home\n\n" + "\n\n".join(BROKEN) + "\n")
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(config))
    res = _mkdocs_build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert res.returncode != 0
    warnings = [line for line in (res.stdout + res.stderr).splitlines() if "WARNING" in line]
    for body, complaint in BROKEN.items():
        assert any(complaint in line for line in warnings), (body, warnings)


def _hooks():
    import importlib.util

    spec = importlib.util.spec_from_file_location("mkdocs_hooks", ROOT / "docsite" / "mkdocs_hooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("source, expected", [
    # CommonMark: a bullet list, or an ordered one from 1, may interrupt a paragraph
    ("Text\n- a\n- b\n", "Text\n\n- a\n- b\n"),
    ("Text\n1. a\n2. b\n", "Text\n\n1. a\n2. b\n"),
    ("Text ends in\n5. which is no list\n", None),
    # a tight list with continuation lines and a nested list stays as it is
    ("- a\n  more of a\n- b\n  - b1\n  - b2\n- c\n", None),
    # the next item after a loose item's second paragraph (or a table) is set apart
    ("- a\n\n  second paragraph of a\n- b\n", "- a\n\n  second paragraph of a\n\n- b\n"),
    # a list after a heading, or after a blank line, needs nothing; code is left alone
    ("## Heading\n- a\n", None),
    ("Text\n\n- a\n", None),
    ("```\ncode\n- not an item\n```\n", None),
    ("Para\n```\nx\n```\nafter\n- a\n", "Para\n```\nx\n```\nafter\n\n- a\n"),
])
def test_lists_after_a_paragraph_line_get_their_blank_line(source, expected):
    assert _hooks().blank_line_before_lists(source) == (source if expected is None else expected)


@pytest.mark.parametrize("source, expected", [
    ("see `fuzzynav.sim.imu` and `fuzzynav.units.DEG`.",
     'see <autoref identifier="fuzzynav.sim.imu" optional><code>fuzzynav.sim.imu</code>'
     '</autoref> and <autoref identifier="fuzzynav.units.DEG" optional><code>fuzzynav.units.DEG'
     '</code></autoref>.'),
    ("# The engine (`fuzzynav.fuzzy`)", None),               # a heading (the nav, the toc)
    ("```\n`fuzzynav.fuzzy`\n```", None),                    # code
    ("[`fuzzynav.fuzzy`](fuzzy.md)", None),                  # already a link
    ("`fuzzynav` and ``fuzzynav.fuzzy`` and `fuzzynav.fuzzy.load_fis()`", None),
])
def test_code_spans_naming_the_package_become_optional_cross_references(source, expected):
    assert _hooks().link_code_paths(source) == (source if expected is None else expected)


def test_the_site_reads_github_lists_as_github_does():
    """With the site's extensions and hook, Python-Markdown finds the items GitHub finds."""
    _need_docs_extra()
    import markdown
    import yaml

    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    names, configs = [], {}
    for ext in config["markdown_extensions"]:
        name, options = next(iter(ext.items())) if isinstance(ext, dict) else (ext, {})
        names.append(name)
        configs[name] = options or {}
    source = ("Refused:\n- **Sizes.** Estimated first.\n  - outages\n  - segments\n"
              "- **Structure.**\n\n  | key | why |\n  |---|---|\n  | a | b |\n\n"
              "  After the table.\n- **Last.**\n")
    html = markdown.markdown(_hooks().blank_line_before_lists(source), extensions=names,
                             extension_configs=configs)
    assert html.count("<li>") == 5 and html.count("<ul>") == 2, html
    assert "<table>" in html and "- " not in html, html


def _roles():
    _need_docs_extra()
    import importlib.util

    import griffe

    spec = importlib.util.spec_from_file_location("sphinx_roles",
                                                  ROOT / "docsite" / "sphinx_roles.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return griffe, module


def test_sphinx_roles_become_links_to_what_the_site_documents(tmp_path, caplog):
    griffe, roles = _roles()
    pkg_dir = tmp_path / "toypkg"
    pkg_dir.mkdir()
    (pkg_dir / "__init__.py").write_text('"""Toy."""\n')
    (pkg_dir / "other.py").write_text(
        '"""Other."""\n\n\nclass Thing:\n    """A thing."""\n\n'
        '    def grow(self):\n        """Grow."""\n\n\nclass Bare:\n    pass\n')
    (pkg_dir / "mod.py").write_text(
        '"""Mod."""\nfrom .other import Thing\n\n\ndef helper():\n    """Help."""\n\n\n'
        'def _hidden():\n    """Private."""\n')
    pkg = griffe.load("toypkg", search_paths=[str(tmp_path)])
    mod = pkg["mod"]
    cases = {
        ":func:`helper`": "[`helper`][toypkg.mod.helper]",          # same module
        ":class:`Thing`": "[`Thing`][toypkg.other.Thing]",          # imported: canonical path
        ":meth:`Thing.grow`": "[`Thing.grow`][toypkg.other.Thing.grow]",
        ":class:`~toypkg.other.Thing`": "[`Thing`][toypkg.other.Thing]",
        ":class:`the thing <toypkg.other.Thing>`": "[`the thing`][toypkg.other.Thing]",
        ":func:`toypkg.mod.\n    helper`": "[`toypkg.mod.helper`][toypkg.mod.helper]",
        ":func:`_hidden`": "`_hidden`",                             # private: not on the site
        ":class:`toypkg.other.Bare`": "`toypkg.other.Bare`",        # undocumented: not either
        ":class:`numpy.ndarray`": "`numpy.ndarray`",                # outside the package
    }
    for role, expected in cases.items():
        assert roles.rewrite(f"See {role}.", mod, pkg) == f"See {expected}.", role
    assert not caplog.records
    with caplog.at_level("WARNING", logger="griffe"):
        assert roles.rewrite(":func:`toypkg.gone`", mod, pkg) == "`toypkg.gone`"
    assert "names no object of the package" in caplog.text
