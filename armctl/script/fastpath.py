"""The regex fast path: the commonest line shapes without Lark.

Strategy: nearly every line of a real job is blank/comment-only or ``G1 X… Y… F… ; comment``:
a G or M code followed by letter-and-literal-number words, with spaces and ( … ) comments in
between.  One anchored regular expression (possessive quantifiers, so no backtracking blow-up
on hostile input) recognises exactly that shape and captures its words in the same pass.
The result is the very node Lark would build (armctl/script/grammar.py), except that word
columns are left out (``spans=None``): they are only needed to point at a word, and the
compiler re-parses a line with Lark whenever it has something to report.

Anything else — expressions, parameters, keywords, blocks, odd characters, and every line
with a syntax error — returns ``None`` and goes to Lark.  So the fast path never rejects a
line, and a differential test (tests/test_script_fastpath.py) checks on generated lines that
whenever it answers, Lark answers the same.
"""

from __future__ import annotations

import re

from .grammar import LETTERS
from .nodes import EMPTY, CodeLine, Node, code_number

_NUMBER = r"[+-]?+(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)"
_LETTER = r"(?:[Jj][1-6]=|[A-Za-z])"
_GAP = r"(?:[ \t]++|\([^)\n]*+\))*+"  # spaces and inline comments
_COMMENT = r"(?:;[^\n]*+)?+"

# Python cannot capture a repeated group, so the words are MAX_WORDS optional groups in a row:
# one pass both validates the line and captures every word.  Words are a prefix of the slots
# (a slot that does not match leaves the next one at the same place, where it cannot match
# either), so match.lastindex tells how many there are.  No valid line has more words than a
# statement has letters (11); a longer line goes to Lark.
MAX_WORDS = 12
_WORD_SLOT = rf"(?:{_GAP}({_LETTER})({_NUMBER}))?+"
_CODE_LINE = re.compile(
    rf"[ \t]*+(?:[Nn][0-9]++{_GAP})?+([GgMm])([0-9]++)" + _WORD_SLOT * MAX_WORDS + rf"{_GAP}{_COMMENT}\Z"
)
_EMPTY_LINE = re.compile(rf"{_GAP}(?:[Nn][0-9]++{_GAP})?+{_COMMENT}\Z")


def scan(text: str):
    """A plain code line's raw parts ``(letter, digits, column, end_column, words)``, where
    ``words`` alternates names and numbers as written (``('X', '10', 'j1=', '-2.5')``);
    ``EMPTY`` for a line with nothing to do; None for anything else (ask Lark).  The
    compiler's hot path uses this directly."""
    match = _CODE_LINE.match(text)
    if match is None:
        return EMPTY if _EMPTY_LINE.match(text) else None
    groups = match.groups()
    return groups[0], groups[1], match.start(1) + 1, match.end(2) + 1, groups[2 : match.lastindex]


def node_from_scan(scanned) -> CodeLine:
    """The ``CodeLine`` for what ``scan`` found (what Lark would build, without word spans)."""
    letter, digits, column, end_column, words = scanned
    names = iter(words)
    return CodeLine(
        letter.upper(), int(digits) if len(digits) < 10 else code_number(digits),
        tuple([(LETTERS[name], float(number)) for name, number in zip(names, names)]), column, end_column,
    )


def parse_fast(text: str) -> Node | None:
    """The node for ``text`` if it has a plain shape, else None (ask Lark)."""
    scanned = scan(text)
    if scanned is None or scanned is EMPTY:
        return scanned
    return node_from_scan(scanned)
