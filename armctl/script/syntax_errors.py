"""Turn Lark's ``UnexpectedInput`` on one line into a plain sentence and a column.

Strategy: the set of terminals the parser would have accepted says *where* in a statement the
line went wrong (at its start, among the words, where a value belongs, inside brackets, where
``=`` belongs, after ``O<label>``, after a complete statement); the characters at the error
column say *what* was found.  Each (context, finding) pair maps to one sentence and, where it
helps, a hint.  No token names ever reach the user.  The column points at the offending
character, or just after the last token when the line ends too early.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # Lark is imported on first use (armctl/script/grammar.py)
    from lark.exceptions import UnexpectedInput

KEYWORDS = ("RESET", "PAUSE", "POSE", "PROGRAM", "MODE")
START_HINT = (
    "start the line with a G or M code (G1 X5), a keyword (RESET, PAUSE, POSE, PROGRAM, MODE), "
    "#<name> = value, or O<label> repeat/endrepeat"
)
VALUE = "a number, #<name> or [expression]"


class LineSyntaxError(Exception):
    """A line that does not parse: code, sentence, columns (1-based, end exclusive), hint."""

    def __init__(self, message: str, column: int, end_column: int, hint: str | None = None, code: str = "E001"):
        super().__init__(message)
        self.code, self.message, self.hint = code, message, hint
        self.column, self.end_column = column, end_column


_LEXEME = re.compile(r"#<[^>\s]*>?|[A-Za-z][A-Za-z0-9_]*=?|[0-9.]+|\S")
_WORD_AT = re.compile(r"([Jj][1-6]=|[A-Za-z])([+-]?([0-9]+\.?[0-9]*|\.[0-9]+))?")
_JOINT = re.compile(r"[Jj][1-6]=")


def _quote(lexeme: str) -> str:
    if lexeme.isprintable():
        return f"'{lexeme}'"
    return repr(lexeme).replace('"', "'")


def _lexeme(rest: str) -> str:
    match = _LEXEME.match(rest)
    return match.group() if match else rest[:1]


def _previous(text: str, column: int) -> str:
    """The last lexeme before ``column`` (ignoring spaces and inline comments)."""
    before = re.sub(r"\([^)]*\)", lambda m: " " * len(m.group()), text[: column - 1]).rstrip()
    match = re.search(r"(#<[^>]*>|[A-Za-z][A-Za-z]*[0-9]*=?[+-]?|O<[^>]*>|\S)$", before)
    return match.group() if match else ""


def _unclosed_bracket(text: str, column: int) -> int | None:
    """The column of the last '[' before ``column`` that no ']' closes."""
    stack: list[int] = []
    in_comment = False
    for index, char in enumerate(text[: column - 1]):
        if in_comment:
            in_comment = char != ")"
        elif char == "(":
            in_comment = True
        elif char == ";":
            break
        elif char == "[":
            stack.append(index + 1)
        elif char == "]" and stack:
            stack.pop()
    return stack[-1] if stack else None


def explain(error: UnexpectedInput, text: str) -> LineSyntaxError:
    """The sentence, columns and hint for a line Lark could not parse."""
    from lark.exceptions import UnexpectedCharacters, UnexpectedToken

    if isinstance(error, UnexpectedToken):
        expected = set(error.expected)
        token = error.token
        if token.type == "$END":
            column = token.end_column if token.end_column else len(text) + 1
            rest = ""
        else:
            column, rest = token.column, text[token.column - 1 :]
    elif isinstance(error, UnexpectedCharacters):
        expected = set(error.allowed or ())
        column, rest = error.column, text[error.column - 1 :]
    else:  # pragma: no cover - LALR raises only the two above
        return LineSyntaxError("this line cannot be read", 1, len(text) + 1)
    # LALR merges look-ahead sets across contexts; the interactive parser knows the exact one.
    interactive = getattr(error, "interactive_parser", None)
    if interactive is not None:
        expected = set(interactive.accepts())
    if rest.startswith("(") and ")" not in rest:
        return LineSyntaxError(
            "comment '(' is not closed on this line", column, column + 1,
            "an inline comment is ( … ) on one line; ; starts a comment to the end of the line",
        )
    for accepts, explainer in _CONTEXTS:
        if accepts(expected):
            return explainer(text, column, rest)
    return _after_statement(text, column, rest)


def _point(column: int, rest: str) -> tuple[int, int]:
    return column, column + (1 if rest else 0)


def _at_start(text: str, column: int, rest: str) -> LineSyntaxError:
    lexeme = _lexeme(rest)
    if rest[:1] == "#":
        if rest[1:2].isdigit():
            return LineSyntaxError(
                "numbered parameters are not supported: name it, as in #<name>", column, column + len(lexeme),
            )
        return LineSyntaxError("expected a parameter name: #<name> (letters, digits and _)", column, column + len(lexeme))
    if rest[:1] in ("G", "g", "M", "m", "N", "n") and not rest[1:2].isdigit():
        after = column + 1
        return LineSyntaxError(f"expected a number after {rest[0].upper()}", *_point(after, rest[1:]))
    if rest[:1] in ("O", "o") and not rest[1:2].isalpha():
        return LineSyntaxError(
            "expected a label after O: O<name> or O123", *_point(column + 1, rest[1:]),
            "blocks are O<label> repeat [n] … O<label> endrepeat",
        )
    word = _WORD_AT.match(rest)
    shown = word.group() if word else lexeme
    return LineSyntaxError(f"a statement cannot start with {_quote(shown)}", column, column + len(shown), START_HINT)


def _among_words(text: str, column: int, rest: str) -> LineSyntaxError:
    joint = _JOINT.match(rest)
    if joint:
        return LineSyntaxError(f"expected a number after {joint.group().upper()}", *_point(column + 3, rest[3:]))
    if rest[:1] == "=" and re.search(r"[Jj][1-6]$", text[: column - 1]):  # J1= lexed as the word J1
        joint_name = text[column - 3 : column - 1].upper()
        return LineSyntaxError(f"expected a number after {joint_name}=", *_point(column + 1, rest[1:]))
    lexeme = _lexeme(rest)
    if lexeme.upper() in KEYWORDS:
        return LineSyntaxError(
            f"one statement per line: {lexeme.upper()} must be on a line of its own", column, column + len(lexeme),
        )
    if rest[:1].isascii() and rest[:1].isalpha():
        after = rest[1:]
        hint = None
        if after[:1] in (" ", "\t") and re.match(r"[ \t]+[+-]?[0-9.#\[]", after):
            hint = f"write the number right after its letter, as in {rest[0].upper()}10"
        return LineSyntaxError(f"expected a number after {rest[0].upper()}", *_point(column + 1, after), hint)
    hint = None
    if rest[:1] in (".",) or (rest[:1].isdigit() and text[column - 2 : column - 1] in ".0123456789"):
        hint = "a number has at most one decimal point"
    elif rest[:1] in ("#", "["):
        hint = "a value needs its letter, as in X#<a> or X[#<a> + 1]"
    return LineSyntaxError(f"expected a word such as X10, found {_quote(lexeme)}", column, column + len(lexeme), hint)


def _where_value(text: str, column: int, rest: str) -> LineSyntaxError:
    previous = _previous(text, column)
    hint = "( … ) is a comment; group an expression with [ ]" if "(" in text else None
    if rest[:1] == "#":
        lexeme = _lexeme(rest)
        return LineSyntaxError("expected a parameter name: #<name> (letters, digits and _)", column, column + len(lexeme))
    return _expected(f"{VALUE} after {_quote(previous)}", column, rest, hint)


def _in_brackets(text: str, column: int, rest: str) -> LineSyntaxError:
    if not rest:
        opening = _unclosed_bracket(text, column)
        where = f" opened at column {opening}" if opening else ""
        return LineSyntaxError(f"missing ']' to close the '['{where}", column, column)
    lexeme = _lexeme(rest)
    hint = "( … ) is a comment; group an expression with [ ]" if "(" in text else None
    return LineSyntaxError(
        f"expected an operator (+ - * /) or ']', found {_quote(lexeme)}", column, column + len(lexeme), hint,
    )


def _where_equals(text: str, column: int, rest: str) -> LineSyntaxError:
    name = _previous(text, column)
    hint = f"{name} = 5 assigns a parameter; a parameter alone is not a statement"
    return _expected(f"'=' after {name}", column, rest, hint)


def _after_label(text: str, column: int, rest: str) -> LineSyntaxError:
    label = _previous(text, column)
    hint = f"blocks are {label} repeat [n] … {label} endrepeat"
    return _expected(f"repeat or endrepeat after {label}", column, rest, hint)


def _expected(what: str, column: int, rest: str, hint: str | None) -> LineSyntaxError:
    """"expected WHAT" at the end of the line, else "expected WHAT, found X" spanning X."""
    if not rest:
        return LineSyntaxError(f"expected {what}", column, column, hint)
    lexeme = _lexeme(rest)
    return LineSyntaxError(f"expected {what}, found {_quote(lexeme)}", column, column + len(lexeme), hint)


def _after_statement(text: str, column: int, rest: str) -> LineSyntaxError:
    lexeme = _lexeme(rest)
    if lexeme in ("+", "-", "*", "/"):
        return LineSyntaxError(
            f"unexpected {_quote(lexeme)}: an expression goes in brackets", column, column + 1,
            "write the value as [expression], as in #<a> = [#<a> + 1]",
        )
    return LineSyntaxError(
        f"unexpected {_quote(lexeme)} after the end of the statement", column, column + len(lexeme),
        "one statement per line",
    )


# (does the expected-terminal set look like this context?, explainer), first match wins.
_CONTEXTS = (
    (lambda e: "CODE" in e, _at_start),
    (lambda e: "WORD" in e, _among_words),
    (lambda e: "NUMBER" in e, _where_value),
    (lambda e: "RSQB" in e, _in_brackets),
    (lambda e: "EQUAL" in e, _where_equals),
    (lambda e: "NAME" in e, _after_label),
)
