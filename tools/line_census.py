"""Line census: what the Python lines of the project are, at any revision, and which
functions are copies of each other.

Counts every ``.py`` file under the given folders (default ``fuzzynav``, ``benchmarks``,
``tools``) line by line as code, docstring, comment or blank, and the lines of ``__all__``
lists, for the working tree or for git revisions (read with ``git show``, nothing checked
out).  ``--copies`` lists the functions whose bodies are the same once names, arguments and
constants are set aside (the AST of the body after its docstring, every name, argument and
literal replaced by one placeholder): the copies a consolidation could still merge, with
the lines merging each group would save.

Usage::

    python tools/line_census.py                      # the working tree
    python tools/line_census.py --rev 9b951ac HEAD   # two revisions side by side
    python tools/line_census.py --copies --min-lines 4
"""
from __future__ import annotations

import argparse
import ast
import copy
import hashlib
import io
import subprocess
import sys
import tokenize
from collections import defaultdict
from pathlib import Path

KINDS = ("code", "docstring", "comment", "blank")
DIRS = ("fuzzynav", "benchmarks", "tools")


def docstring_lines(tree: ast.AST) -> set:
    """Line numbers (1-based) of every module, class and function docstring."""
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                    and isinstance(body[0].value.value, str):
                lines.update(range(body[0].lineno, body[0].end_lineno + 1))
    return lines


def _comment_only_lines(text: str) -> set:
    """Lines holding a comment token and no code token (the tokenizer, so a ``#`` inside
    a string is not a comment)."""
    comments, code = set(), set()
    skip = (tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
            tokenize.ENDMARKER, tokenize.ENCODING)
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.COMMENT:
            comments.add(tok.start[0])
        elif tok.type not in skip:
            code.update(range(tok.start[0], tok.end[0] + 1))
    return comments - code


def census(text: str) -> dict:
    """Counts of one source file: ``code``, ``docstring``, ``comment``, ``blank`` (they sum
    to its lines) and ``all`` (lines of ``__all__`` assignments, counted in ``code`` too)."""
    tree = ast.parse(text)
    doc = docstring_lines(tree)
    comment = _comment_only_lines(text)
    counts = dict.fromkeys(KINDS, 0)
    for i, line in enumerate(text.splitlines(), 1):
        kind = "docstring" if i in doc else "blank" if not line.strip() else \
            "comment" if i in comment else "code"
        counts[kind] += 1
    counts["all"] = sum(n.end_lineno - n.lineno + 1 for n in tree.body
                        if isinstance(n, ast.Assign)
                        and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets))
    return counts


class _Shape(ast.NodeTransformer):
    """Every name, argument and constant the same placeholder: what is left is the shape."""

    def visit_Name(self, node):
        return ast.Name(id="_", ctx=ast.Load())

    def visit_arg(self, node):
        return ast.arg(arg="_")

    def visit_Constant(self, node):
        return ast.Constant(value=0)


def body_key(fn: ast.FunctionDef) -> str:
    """A digest of a function's body after its docstring, names and constants abstracted."""
    body = fn.body
    if len(body) > 1 and isinstance(body[0], ast.Expr) and isinstance(body[0].value,
                                                                      ast.Constant):
        body = body[1:]  # a docstring; a function that is only one still has a shape
    dumped = "".join(ast.dump(_Shape().visit(copy.deepcopy(b))) for b in body)
    return hashlib.sha1(dumped.encode()).hexdigest()


def copies(sources: dict, min_lines: int = 4) -> list:
    """Groups of functions of at least ``min_lines`` lines with the same body shape:
    ``[(lines saved by keeping one, [(lines, "path:line:name"), ...]), ...]``, most first."""
    groups = defaultdict(list)
    for path, text in sources.items():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                size = node.end_lineno - node.lineno + 1
                if size >= min_lines:
                    groups[body_key(node)].append((size, f"{path}:{node.lineno}:{node.name}"))
    found = [(sum(s for s, _ in g) - max(s for s, _ in g), sorted(g, key=lambda x: x[1]))
             for g in groups.values() if len(g) > 1]
    return sorted(found, reverse=True)


def sources_at(rev: str | None, dirs, root: Path) -> dict:
    """``path -> text`` of the ``.py`` files under ``dirs``, in the working tree (``rev``
    None) or at a git revision."""
    if rev is None:
        return {str(p.relative_to(root)): p.read_text(encoding="utf-8")
                for d in dirs for p in sorted((root / d).rglob("*.py"))}
    names = subprocess.run(["git", "-C", str(root), "ls-tree", "-r", "--name-only", rev, "--",
                            *dirs], check=True, capture_output=True, text=True).stdout.split()
    return {n: subprocess.run(["git", "-C", str(root), "show", f"{rev}:{n}"], check=True,
                              capture_output=True, text=True).stdout
            for n in names if n.endswith(".py")}


def totals(sources: dict, dirs) -> dict:
    """``folder -> counts`` (:func:`census` summed, plus ``files`` and ``lines``)."""
    out = {d: dict.fromkeys(("files", "lines", *KINDS, "all"), 0) for d in dirs}
    for path, text in sources.items():
        row = out[path.split("/", 1)[0]]
        c = census(text)
        row["files"] += 1
        row["lines"] += sum(c[k] for k in KINDS)
        for k, v in c.items():
            row[k] += v
    return out


def table(revs, dirs, root: Path) -> str:
    """A Markdown table: one row per revision and folder."""
    head = ["revision", "folder", "files", "lines", *KINDS, "`__all__`"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for rev in revs:
        for d, row in totals(sources_at(rev, dirs, root), dirs).items():
            cells = [rev or "working tree", f"`{d}/`", *(f"{row[k]:,}" for k in
                                                         ("files", "lines", *KINDS, "all"))]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rev", nargs="*", default=[None], help="git revisions (default: the "
                   "working tree)")
    p.add_argument("--dirs", nargs="*", default=list(DIRS), help="top-level folders counted")
    p.add_argument("--copies", action="store_true", help="list functions whose bodies are "
                   "the same but for names and constants (in the first revision)")
    p.add_argument("--min-lines", type=int, default=4, help="smallest function --copies "
                   "lists (default 4)")
    args = p.parse_args(argv)
    root = Path(__file__).resolve().parent.parent
    print(table(args.rev, args.dirs, root))
    if args.copies:
        found = copies(sources_at(args.rev[0], args.dirs, root), args.min_lines)
        print(f"\n{len(found)} group(s) of same-shape function bodies of >= {args.min_lines} "
              f"lines; merging each into one would save {sum(s for s, _ in found)} lines")
        for saved, group in found:
            print(f"  {saved:4d}  " + "  ~  ".join(f"{where} ({n})" for n, where in group))
    return 0


if __name__ == "__main__":
    sys.exit(main())
