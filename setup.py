"""Build hook: a wheel (``pip install .``) ships the repository's ``rules/`` as package data.

``rules/`` at the repository root stays the one copy of the rule files (studies, tests and
docs name ``rules/...``); building a wheel copies its ``*.json`` into ``fuzzynav/rules``,
where :func:`fuzzynav.filters.catalog.rules_dirs` looks last.  An editable install reads
``rules/`` in the checkout instead.  Everything else is in ``pyproject.toml``.
"""
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

RULES = Path(__file__).resolve().parent / "rules"


class BuildPyWithRules(build_py):
    """``build_py`` that also copies ``rules/*.json`` into the built package."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        target = Path(self.build_lib) / "fuzzynav" / "rules"
        self.mkpath(str(target))
        for src in sorted(RULES.glob("*.json")):
            self.copy_file(str(src), str(target / src.name))


setup(cmdclass={"build_py": BuildPyWithRules})
