"""The regex fast path: the commonest line shapes without Lark.

Strategy: nearly every line of a real job is blank/comment-only or ``G1 X… Y… F… ; comment``:
a G or M code followed by letter-and-literal-number words, with spaces and ( … ) comments in
between.  One anchored regular expression (possessive quantifiers, so no backtracking blow-up
on hostile input) recognises exactly that shape and captures its words in the same pass.
The result is the very node Lark would build (armctl/script/grammar.py), except that word
columns are left out (``spans=None``): they are only needed to point at a word, and the
compiler re-parses a line with Lark whenever it has something to report.

A second, slower fast path (``parse_expression_line``) reads the next commonest shapes — a
code line whose words may be ``#<name>``, ``[expression]`` or a signed one, and ``#<name> =
value`` — by recursive descent over one tokenizer regex, and builds Lark's node exactly, word
columns and expression columns included (Lark costs ~100 µs a line of the benchmark script
here, this ~13). In front of it, the commonest of those — words whose value is a literal, a
``#<name>`` or ``[a op b]`` of two such operands — are read a word at a time with one match
each (``_simple_line``: ~5 µs a line of benchmarks/cli_speed.py's expression script, the
general reader ~13, measured one after the other); anything else falls through to the general
reader. The nodes of its expression words are kept by (text, column) and shared by the lines
that repeat them (nodes are immutable; at most MAX_WORD_VALUES): fewer objects built is ~0.15
s of a 50k-line compile. The same rules hold: anything else (keywords, blocks, deep nesting,
every syntax error) returns ``None`` and goes to Lark, and the differential test holds it to
Lark too.

Anything else — keywords, blocks, odd characters, and every line with a syntax error —
returns ``None`` and goes to Lark.  So neither fast path ever rejects a line, and a
differential test (tests/test_script_fastpath.py) checks on generated lines that whenever
one answers, Lark answers the same.
"""

from __future__ import annotations

import re

from .expressions import Binary, Negate, Parameter
from .grammar import LETTERS, MAX_EXPRESSION_DEPTH
from .nodes import EMPTY, Assignment, CodeLine, Node, code_number

_NUMBER = r"[+-]?+(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)"
_LETTER = r"(?:[Jj][1-6]=|[A-Za-z])"
# spaces and inline comments: a run of spaces, then any comments each followed by spaces (the
# same strings as "(?:spaces|comment)*", matched without trying the alternation at every space)
_GAP = r"[ \t]*+(?:\([^)\n]*+\)[ \t]*+)*+"
_COMMENT = r"(?:;[^\n]*+)?+"

# Python cannot capture a repeated group, so the words are MAX_WORDS optional groups, each
# nested in the one before: one pass both validates the line and captures every word.  Words
# are a prefix of the slots, so match.lastindex tells how many there are, and the first slot
# that does not match ends the words without the later slots being tried.  No valid line has
# more words than a statement has letters (11); a longer line goes to Lark.  The word letter is
# _LETTER with the common letters tried first (J alone or J1= … J6= last): the same matches.
MAX_WORDS = 12
_WORD = rf"{_GAP}([A-IK-Za-ik-z]|[Jj](?:[1-6]=)?)({_NUMBER})"
_WORD_SLOTS = ""
for _ in range(MAX_WORDS):
    _WORD_SLOTS = rf"(?:{_WORD}{_WORD_SLOTS})?+"
_CODE_LINE = re.compile(rf"[ \t]*+(?:[Nn][0-9]++{_GAP})?+([GgMm])([0-9]++){_WORD_SLOTS}{_GAP}{_COMMENT}\Z")
_EMPTY_LINE = re.compile(rf"{_GAP}(?:[Nn][0-9]++{_GAP})?+{_COMMENT}\Z")


def scan(text: str):
    """A plain code line's raw parts ``(letter, digits, column, end_column, words)``, where
    ``words`` alternates names and numbers as written (``('X', '10', 'j1=', '-2.5')``);
    ``EMPTY`` for a line with nothing to do; None for anything else (ask Lark).  The
    compiler's hot path uses this directly."""
    match = _CODE_LINE.match(text)
    if match is None:
        return EMPTY if _EMPTY_LINE.match(text) else None
    return scanned_parts(match)


# the compiler's hot path matches first, then asks scanned_parts (or, with no match, match_empty_line)
match_code_line, match_empty_line = _CODE_LINE.match, _EMPTY_LINE.match


def scanned_parts(match):
    """``scan``'s answer for a line ``match_code_line`` matched."""
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


# --- expression lines: the common shapes, one match a line --------------------------------------

# Most expression lines are made of words whose value is a literal, a #<name>, or one operation
# on two of those in brackets (``X[#<x> + 0.5]``, ``#<x> = [#<x> + -1.5]``).  Those lines are
# read a word at a time, one match a word (spaces only inside the brackets), and every column
# comes from the match's group positions: no token list, no recursive descent.  Any other line
# — a comment or a sign inside brackets, nesting, two operators, ``X-#<a>`` — leaves something
# after the last word the end pattern does not match, and goes to the general reader below,
# which handles it or declines.  (One pattern for the whole line, word slots nested as in
# _CODE_LINE, matched no faster and took 8 ms to compile at start-up.)  Issue 13: this is
# about 1.8 times as fast as the general reader on these lines.
_PARAMETER = r"#<[A-Za-z_][A-Za-z0-9_]*+>"
_UNSIGNED = r"(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)"
# an operand: a number with at most one minus written against it (folded into the number, at
# the minus's column, as the grammar's negate of a number is), or a parameter
_ATOM = rf"(?:(-?+{_UNSIGNED})|({_PARAMETER}))"
_SPACES = r"[ \t]*+"
# a value, 7 groups: a parameter, or [atom op atom] (the whole bracket, then each part)
_SIMPLE_VALUE = rf"(?:({_PARAMETER})|(\[{_SPACES}{_ATOM}{_SPACES}([-+*/]){_SPACES}{_ATOM}{_SPACES}\]))"
_SIMPLE_CODE = re.compile(rf"[ \t]*+(?:[Nn][0-9]++{_GAP})?+([GgMm][0-9]++)")
# a word, 9 groups: the letter, a literal number, then _SIMPLE_VALUE's 7
_SIMPLE_WORD = re.compile(rf"{_GAP}({_LETTER})(?:({_NUMBER})|{_SIMPLE_VALUE})")
_SIMPLE_END = re.compile(rf"{_GAP}{_COMMENT}\Z")
# #<name> = value (group 2, its columns): a signed literal (the minus folded in, as above), or
# a _SIMPLE_VALUE
_SIMPLE_ASSIGNMENT = re.compile(
    rf"[ \t]*+(?:[Nn][0-9]++{_GAP})?+({_PARAMETER}){_GAP}={_GAP}((-?+{_UNSIGNED})|{_SIMPLE_VALUE}){_GAP}{_COMMENT}\Z"
)


# The nodes of expression words already read, by (text, column): a script repeats the same
# words line after line (``G1 X[#<x> + 0.5] Y#<y>`` after each step's assignments), and a node
# is immutable, so one serves every line that writes it there.  At most MAX_WORD_VALUES.
MAX_WORD_VALUES = 4096
_WORD_VALUES: dict = {}


def _simple_value(groups: tuple, span, at: int):
    """The node of a matched _SIMPLE_VALUE whose groups start at ``groups[at]`` (group ``at + 1``
    of the match whose ``span`` method is given), with the columns Lark gives."""
    name = groups[at]
    if name is not None:
        start, end = span(at + 1)
        return Parameter(name[2:-1].lower(), start + 1, end + 1)
    number = groups[at + 2]
    if number is not None:
        left, column = float(number), span(at + 3)[0] + 1
    else:
        start, end = span(at + 4)
        column = start + 1
        left = Parameter(groups[at + 3][2:-1].lower(), column, end + 1)
    number = groups[at + 5]
    if number is not None:
        right, end = float(number), span(at + 6)[1]
    else:
        start, end = span(at + 7)
        right = Parameter(groups[at + 6][2:-1].lower(), start + 1, end + 1)
    return Binary(groups[at + 4], left, right, column, end + 1)


def _simple_line(text: str):
    """The node for a line of the common expression shapes (see above), else None."""
    match = _SIMPLE_CODE.match(text)
    if match is not None:
        code, column, end_column = match.group(1), match.start(1) + 1, match.end(1) + 1
        words, spans = [], []
        word_match, position = _SIMPLE_WORD.match, match.end()
        while (match := word_match(text, position)) is not None:
            groups = match.groups()
            number = groups[1]
            position = match.end()
            if number is not None:
                value = float(number)
            else:  # a node is fixed by its text and where it starts (the letter's end)
                key = (groups[2] or groups[3], match.end(1))
                value = _WORD_VALUES.get(key)
                if value is None:
                    if len(_WORD_VALUES) >= MAX_WORD_VALUES:
                        _WORD_VALUES.clear()
                    value = _WORD_VALUES[key] = _simple_value(groups, match.span, 2)
            words.append((LETTERS[groups[0]], value))
            spans.append((match.start(1) + 1, position + 1))
        if _SIMPLE_END.match(text, position) is None:
            return None
        return CodeLine(code[0].upper(), code_number(code[1:]), tuple(words), column, end_column, tuple(spans))
    match = _SIMPLE_ASSIGNMENT.match(text)
    if match is None:
        return None
    groups = match.groups()
    start, end = match.span(2)
    number = groups[2]
    value = float(number) if number is not None else _simple_value(groups, match.span, 3)
    return Assignment(groups[0][2:-1].lower(), value, match.start(1) + 1, end + 1, (start + 1, end + 1))


# --- expression lines: the general reader ------------------------------------------------------

# The line's head: an optional line number, then a G/M code or the #<name> of an assignment.
# (The general reader's two patterns are compiled on first use, through re's cache: most
# scripts never need them, and compiling them cost every start-up 0.6 ms.)
_HEAD = rf"[ \t]*+(?:[Nn][0-9]++{_GAP})?+(?:([GgMm][0-9]++)|(#<[A-Za-z_][A-Za-z0-9_]*+>))"
# The tokens after it, as grammars/armctl.lark spells its terminals, each after what Lark
# ignores (spaces, ( … ) and ; comments); what a token is follows from its first character,
# so these context-free tokens are the ones Lark's contextual lexer finds wherever the parser
# below accepts them.  In a word the prefix comes first: it is Lark's WORD_PREFIX.2, which
# outranks WORD (the "J1" of "J1=#<a>").  Anything else is one "other" character: ask Lark.
# No token starts with a letter, nor two tokens with one character, so the order of the
# alternatives changes no match: the tokens are tried first, commonest first (issue 13: this
# pattern is most of the expression fast path's time).
_TOKENS = (
    r"([ \t]*+)(?:(#<[A-Za-z_][A-Za-z0-9_]*+>|[-+*/\[\]=]|[0-9]++\.?+[0-9]*+|\.[0-9]++|\([^)\n]*+\)|;[^\n]*+|\Z)"
    rf"|({_LETTER})(?:({_NUMBER})|(?=[+-]?[#\[]))|(.))"
)
_MAX_NESTING = 50  # brackets deep; deeper (legal or not) goes to Lark


class _Decline(Exception):
    """The line is not one the expression fast path reads: ask Lark."""


def _tokens(text: str, position: int) -> list:
    """(kind, text, column, end_column) for each token from ``position``; kinds: 'p' a word
    prefix, 'w' a literal word (text: (letter, number)), 'n' a number, '#' a parameter, the
    sign itself for - + * / [ ] =, and a last 'e' (end of line)."""
    items = []
    append = items.append
    position += 1  # columns are 1-based, like Lark's
    # the groups are alternatives: one of letter, token and other is set, or none (the end);
    # the commonest (token) is tested first
    for spaces, token, letter, number, other in re.compile(_TOKENS).findall(text, position - 1):
        if spaces:
            position += len(spaces)
        if token:
            end = position + len(token)
            first = token[0]
            if first == "#":
                append(("#", token, position, end))
            elif first in "-+*/[]=":
                append((first, token, position, end))
            elif first in "(;":
                pass  # a comment: Lark ignores it
            else:
                append(("n", token, position, end))
        elif letter:
            end = position + len(letter) + len(number)
            append(("w", (letter, number), position, end) if number else ("p", letter, position, end))
        elif other:
            raise _Decline
        else:
            append(("e", "", position, position))
            return items
        position = end
    raise _Decline  # pragma: no cover - the pattern always ends with the end of the line


def _deeper(node, column: int, end: int, depth: int) -> tuple:
    if depth > MAX_EXPRESSION_DEPTH:
        raise _Decline  # Lark says why
    return node, column, end, depth


def _operand(tokens: list, at: int, nesting: int) -> tuple:
    """A value with its unary signs (grammar: ``value`` and ``signed`` are alike): -x negates
    (a number folds into a number), +x is x.  Returns ((node, column, end, depth), next)."""
    kind, text, column, end = tokens[at]
    if kind == "#":  # the common cases first, without the general machinery below
        return (Parameter(text[2:-1].lower(), column, end), column, end, 0), at + 1
    if kind == "n":
        return (float(text), column, end, 0), at + 1
    if kind == "[" and nesting < _MAX_NESTING:  # the general case below without signs
        inner, at = _sum(tokens, at + 1, nesting + 1)
        closing = tokens[at]
        if closing[0] != "]":
            raise _Decline
        return (inner[0], column, closing[3], inner[3]), at + 1
    signs = []
    while kind == "-" or kind == "+":
        signs.append(tokens[at])
        at += 1
        kind = tokens[at][0]
    _, text, column, end = tokens[at]
    if kind == "n":
        operand = (float(text), column, end, 0)
        at += 1
    elif kind == "#":
        operand = (Parameter(text[2:-1].lower(), column, end), column, end, 0)
        at += 1
    elif kind == "[" and nesting < _MAX_NESTING:
        inner, at = _sum(tokens, at + 1, nesting + 1)
        closing = tokens[at]
        if closing[0] != "]":
            raise _Decline
        operand = (inner[0], column, closing[3], inner[3])
        at += 1
    else:
        raise _Decline
    for sign in reversed(signs):
        if sign[0] == "-":
            node, _, end, depth = operand
            if type(node) is float:
                operand = (-node, sign[2], end, 0)
            else:
                operand = _deeper(Negate(node, sign[2], end), sign[2], end, depth + 1)
    return operand, at


def _binary(operator: str, left: tuple, right: tuple) -> tuple:
    depth = max(left[3], right[3]) + 1
    if depth > MAX_EXPRESSION_DEPTH:
        raise _Decline  # Lark says why
    return Binary(operator, left[0], right[0], left[1], right[2]), left[1], right[2], depth


def _sum(tokens: list, at: int, nesting: int) -> tuple:
    """Inside brackets: products joined by + and -, operands joined by * and /, both left
    to right.  Returns ((node, column, end, depth), next)."""
    left, at = _operand(tokens, at, nesting)
    pending = None  # (operator, left side) of a + or - waiting for its right-hand product
    while True:
        kind = tokens[at][0]
        if kind == "*" or kind == "/":
            right, at = _operand(tokens, at + 1, nesting)
            left = _binary(kind, left, right)
        elif kind == "+" or kind == "-":
            if pending is not None:
                left = _binary(pending[0], pending[1], left)
            pending = (kind, left)
            left, at = _operand(tokens, at + 1, nesting)
        else:
            break
    if pending is not None:
        left = _binary(pending[0], pending[1], left)
    return left, at


def parse_expression_line(text: str) -> Node | None:
    """The node Lark builds for a code line with expression words or an assignment, columns
    included; None for any other line or any doubt (then ask Lark)."""
    node = _simple_line(text)
    if node is not None:
        return node
    head = re.match(_HEAD, text)
    if head is None:
        return None
    try:
        tokens = _tokens(text, head.end())
        code = head.group(1)
        if code is None:  # #<name> = value
            if tokens[0][0] != "=":
                return None
            value, at = _operand(tokens, 1, 0)
            if tokens[at][0] != "e":
                return None
            name = head.group(2)
            return Assignment(name[2:-1].lower(), value[0], head.start(2) + 1, value[2], (value[1], value[2]))
        words, spans, at = [], [], 0
        while True:
            kind, word, column, end = tokens[at]
            if kind == "w":
                words.append((LETTERS[word[0]], float(word[1])))
                spans.append((column, end))
                at += 1
            elif kind == "p":
                value, at = _operand(tokens, at + 1, 0)
                words.append((LETTERS[word], value[0]))
                spans.append((column, value[2]))
            elif kind == "e":
                break
            else:
                return None
    except _Decline:
        return None
    return CodeLine(code[0].upper(), code_number(code[1:]), tuple(words), head.start(1) + 1, head.end(1) + 1, tuple(spans))
