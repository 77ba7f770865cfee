"""Lint: no literal index into the error-state or navigation-state vectors outside the layouts.

Offsets come from ``fuzzynav.filters.layout`` (error state) and ``fuzzynav.nav.state_layout``
(``nav`` and the strapdown work array ``prev``).  The patterns below catch the forms the
code used before (``nav[7]``, ``x[9 + j]``, ``H[m, 6 + i]``, ``F[5, 6]``, ``nav[:, 7:10]``,
``blk_start[b] - 9``) on the names that hold such vectors; small fixed matrices (``C[0, 1]``,
``J[2, j]``) and data rows are other names and pass.  A line that must index literally says
why with a ``# layout: ok`` comment.
"""
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "fuzzynav"
SCANNED = [ROOT / "filters", ROOT / "nav", ROOT / "align"]
LAYOUT_MODULES = {ROOT / "filters" / "layout.py", ROOT / "nav" / "state_layout.py"}
ALLOW = "layout: ok"

_VEC = r"(?<![\w.])(?:x|xs|nav|prev|out_nav|out_xs|out_sig|sigma|sensor_states|P0|qd|q_diag)"
# matrices whose rows are states, and those whose columns are (H rows are measurement rows)
_ROWS = r"(?<![\w.])(?:F|P|Phi|Qd|Qacc|AP|K|PHt|APHt)"
_COLS = r"(?<![\w.])(?:H|F|P|Phi|Qd|Qacc|AP)"
PATTERNS = [
    re.compile(_VEC + r"\[\s*\d"),                      # nav[7], x[9 + j]
    re.compile(_VEC + r"\[\s*:\s*,\s*\d"),              # nav[:, 7:10]
    re.compile(_ROWS + r"\[\s*\d"),                     # F[5, 6]
    re.compile(_COLS + r"\[[^\[\],]+,\s*\d"),           # H[m, 6 + i], F[i, 6]
    re.compile(r"blk_start\[[^\]]*\]\s*[-+]\s*\d"),     # blk_start[b] - 9
]


def code_lines(text: str):
    """``(line number, code without strings and comments, comment)`` of each source line."""
    code, comments = {}, {}
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string
        elif tok.type not in (tokenize.STRING, tokenize.NL, tokenize.NEWLINE,
                              tokenize.INDENT, tokenize.DEDENT, tokenize.ENDMARKER):
            code.setdefault(tok.start[0], []).append(tok.string)
    return [(n, " ".join(parts), comments.get(n, "")) for n, parts in sorted(code.items())]


def offences(text: str):
    """Lines of ``text`` that index a state or nav vector with a literal."""
    out = []
    for n, code, comment in code_lines(text):
        # tokens are joined with spaces: undo it around brackets so the patterns read naturally
        code = re.sub(r"\s*([\[\]:,])\s*", r"\1 ", code).replace("[ ", "[")
        if ALLOW not in comment and any(p.search(code) for p in PATTERNS):
            out.append((n, code))
    return out


@pytest.mark.parametrize("bad", ["a = nav[7]", "xs[j] += x[9 + j]", "H[m, 6 + i] = 1.0",
                                 "F[5, 6] += g", "lla = nav[:, 7:10]", "s0 = blk_start[b] - 9",
                                 "c = F[i, 6]", "prev[12] = 0.0"])
def test_the_lint_catches_literal_indices(bad):
    assert offences(bad + "\n")


@pytest.mark.parametrize("good", ["c = C[0, 1]", "H[0, X_ATT + j] = J[2, j]", "r = row[6 + i]",
                                  "nav[NAV_LAT] -= dlat", "q = x[X_POS + 2]", "z[m] = res[i]",
                                  "s = '''nav[7]'''", "a = nav[7]  # layout: ok (a test)",
                                  "F[r0, c0 + 1] += -z", "out[0] = 1.0"])
def test_the_lint_passes_named_and_small_matrix_indexing(good):
    assert not offences(good + "\n")


def test_no_literal_state_or_nav_index_in_filters_and_nav():
    found = []
    for folder in SCANNED:
        for path in sorted(folder.rglob("*.py")):
            if path in LAYOUT_MODULES:
                continue
            for n, code in offences(path.read_text(encoding="utf-8")):
                found.append(f"{path.relative_to(ROOT.parent)}:{n}: {code}")
    assert not found, "literal state/nav indices (use the named layouts):\n" + "\n".join(found)
