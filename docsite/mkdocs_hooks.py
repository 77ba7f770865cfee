"""mkdocs hooks (``hooks:`` in mkdocs.yml): render the GitHub-flavoured pages as GitHub does.

The pages are written for GitHub, where a bullet list may follow a paragraph line directly
(CommonMark lets a bullet item, or an ordered one numbered 1, interrupt a paragraph).
Python-Markdown needs a blank line first and otherwise runs the items into the paragraph.
The hook adds that blank line on the site; the pages themselves stay as they are.  (Lists
nested by two spaces are the ``mdx_truly_sane_lists`` extension's part.)  It also makes a
code span naming a ``fuzzynav.`` path a link to that object's section of the API reference,
when it has one (an optional cross-reference: plain code otherwise).
"""
from __future__ import annotations

import re

_ITEM = re.compile(r" {0,3}(?:[-*+]|\d{1,9}[.)])(?: |$)")
_INTERRUPTS = re.compile(r" {0,3}(?:[-*+]|1[.)]) +\S")  # items that may interrupt a paragraph
_FENCE = re.compile(r" *(`{3,}|~{3,})")
_CODE_PATH = re.compile(r"(?<![\[`])`(fuzzynav(?:\.[A-Za-z_]\w*)+)`(?![`\]])")


def blank_line_before_lists(markdown: str) -> str:
    """Insert a blank line where a list item directly follows a paragraph line.

    Two cases: a list that interrupts a paragraph, and the next item of a list after a
    paragraph of an item that follows a blank line (a loose item's second paragraph, a line
    after a table in an item).  Python-Markdown runs the item into that paragraph.

    Parameters
    ----------
    markdown : str
        Page source.

    Returns
    -------
    str
        The same source with those blank lines added; code fences are left alone, and so
        are items continuing a tight list.
    """
    out: list[str] = []
    fence = ""          # the open fence's marker, "" outside code
    in_list = False     # inside a list (its items and their continuation lines)
    prev_text = False   # the previous line is a paragraph (or list item) line
    loose = False       # ... of a block that began after a blank line, not with an item
    prev_blank = True
    for line in markdown.split("\n"):
        if fence:
            fence = "" if line.strip().startswith(fence) else fence
        elif (m := _FENCE.match(line)):
            fence, prev_text, prev_blank = m.group(1), False, False
        elif not line.strip():
            prev_text, prev_blank = False, True
        else:
            heading = line.lstrip().startswith("#")
            if _ITEM.match(line):
                if prev_text and (loose or not in_list and _INTERRUPTS.match(line)):
                    out.append("")
                in_list, loose = True, False
            elif prev_blank:
                in_list = in_list and line.startswith(" ") and not heading
                loose = in_list
            prev_text, prev_blank = not heading, False
        out.append(line)
    return "\n".join(out)


def link_code_paths(markdown: str) -> str:
    """Make every code span naming a ``fuzzynav.`` path an optional cross-reference.

    Parameters
    ----------
    markdown : str
        Page source.

    Returns
    -------
    str
        The source with `` `fuzzynav.x.y` `` outside code fences and headings replaced by an
        ``<autoref optional>`` element, which mkdocs-autorefs turns into a link to the API
        reference's section for ``fuzzynav.x.y`` when there is one and into the code span
        alone when not.
    """
    out, fence = [], ""
    for line in markdown.split("\n"):
        if fence:
            fence = "" if line.strip().startswith(fence) else fence
        elif (m := _FENCE.match(line)):
            fence = m.group(1)
        elif not line.lstrip().startswith("#"):
            line = _CODE_PATH.sub(r'<autoref identifier="\1" optional><code>\1</code></autoref>',
                                  line)
        out.append(line)
    return "\n".join(out)


def on_page_markdown(markdown: str, **kwargs) -> str:
    """mkdocs event: the page's Markdown, before it is converted."""
    return link_code_paths(blank_line_before_lists(markdown))
