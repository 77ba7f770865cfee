"""``fuzzynav docs list | regenerate``: the docs results pages, made from the package."""
from __future__ import annotations

from pathlib import Path

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("docs", help="the docs results pages: list them, regenerate them")
    ds = p.add_subparsers(dest="docs_command", metavar="ACTION")
    ds.required = True
    ls = ds.add_parser("list", help="the pages: name, docs file, section and what it shows")
    ls.set_defaults(func=_cmd_list)
    r = ds.add_parser("regenerate", help="rerun a page's experiments and rewrite its section")
    r.add_argument("pages", nargs="+", metavar="PAGE", help="page name (fuzzynav docs list)")
    r.add_argument("--budget", choices=("small", "full"), default="full",
                   help="full: the Monte-Carlo counts and study budgets the page states "
                        "(default); small: a quick look, written to --out")
    r.add_argument("--out", metavar="DIR", type=Path,
                   help="write PAGE.md and figures/ into DIR instead of over docs/ "
                        "(required with --budget small)")
    r.add_argument("--work", metavar="DIR", type=Path,
                   help="keep the page's study journals in DIR: a rerun after an "
                        "interruption resumes them (pages that run studies: science)")
    r.add_argument("--only", metavar="PART[,PART]",
                   help="rerun only these parts of the page (fuzzynav docs list shows them) "
                        "and splice them in, the rest of the page untouched (full budget, "
                        "over docs/)")
    r.set_defaults(func=_cmd_regenerate)


def _cmd_list(args) -> int:
    from fuzzynav.pages.page_registry import PAGES

    for page in PAGES.values():
        where = page.doc + (f" [{page.marker}]" if page.marker else " [whole page]")
        print(f"{page.name:10s} {where:32s} {page.summary}")
        for part, what in page.parts.items():
            print(f"{'':10s}   --only {part}: {what}")
    return 0


def _cmd_regenerate(args) -> int:
    from fuzzynav.pages.page_registry import get_page, regenerate

    from fuzzynav.errors import FuzzynavError
    from fuzzynav.pages.page_registry import regenerate_parts

    pages = [get_page(name) for name in args.pages]  # every name checked before any run
    if args.only is not None:
        if len(pages) != 1 or args.budget != "full" or args.out or args.work:
            raise FuzzynavError("--only reruns parts of one page at the full budget over "
                                "docs/: give one PAGE, no --budget small, --out or --work")
        print(f"wrote {regenerate_parts(pages[0], [p for p in args.only.split(',') if p])}")
        return 0
    for page in pages:
        print(f"wrote {regenerate(page, args.budget, args.out, work=args.work)}")
    return 0
