"""What one parsed source line is: frozen nodes carrying their columns.

Strategy: each line parses on its own into exactly one of ``CodeLine`` (G/M code and words),
``KeywordLine`` (RESET, PAUSE, POSE 2 …), ``Assignment`` (#<name> = value) or ``BlockLine``
(O<label> repeat/endrepeat), or into ``EMPTY`` (blank, comments, a lone N number).  Nodes
say what was *written*: which statement, which words in which order, their values as numbers
or expressions (armctl/script/expressions.py) — never what they mean.  Columns are 1-based,
``end_column`` exclusive.

A ``CodeLine`` from the regex fast path has ``spans=None`` (it skips computing word columns,
which only diagnostics need); the compiler re-parses such a line with Lark when it has to
point at a word.  ``spans`` is excluded from equality, so a fast-path node equals the Lark one.
"""

from __future__ import annotations

from dataclasses import field
from typing import Optional, Union

from ..core.records import record
from .expressions import Value

Span = tuple[int, int]  # (column, end_column)

# A code number too long to be one (more digits than any range) is stored as this; messages
# quote the source text instead.
HUGE_CODE_NUMBER = 10**18


def code_number(digits: str) -> int:
    """The number of a G or M code from its digits, without ever converting a huge string."""
    stripped = digits.lstrip("0")
    return int(stripped or "0") if len(stripped) <= 18 else HUGE_CODE_NUMBER


@record(frozen=False, slots=True)
class CodeLine:
    """``G1 X10 Y-2 J1=[#<a> + 1]`` — a G or M code and its words in source order.

    ``words`` pairs each upper-case letter (``'X'``, ``'J1'``) with its value; ``spans`` gives
    each word's columns, or is None when the fast path parsed the line.  Read-only by
    convention rather than ``frozen=True``: one is built per line on the compiler's hot path,
    and a frozen dataclass takes four times as long to construct.
    """

    letter: str
    number: int
    words: tuple[tuple[str, Value], ...]
    column: int
    end_column: int
    spans: Optional[tuple[Span, ...]] = field(default=None, compare=False)

    @property
    def code(self) -> str:
        return f"{self.letter}{self.number}"


@record(slots=True)
class KeywordLine:
    """``RESET``, ``RESET CONNECTOR``, ``PAUSE``, ``POSE 2``, ``PROGRAM 5``, ``MODE 1`` — or an
    unknown name, which the compiler reports.  ``names`` are upper-case."""

    names: tuple[str, ...]
    argument: Optional[Value]
    column: int
    end_column: int
    argument_span: Optional[Span] = None

    @property
    def keyword(self) -> str:
        return " ".join(self.names)


@record(slots=True)
class Assignment:
    """``#<name> = value`` (``name`` lower-case, without ``#<`` ``>``)."""

    name: str
    value: Value
    column: int
    end_column: int
    value_span: Span


@record(slots=True)
class BlockLine:
    """``O<label> repeat [n]`` or ``O<label> endrepeat`` (``label`` as ``O<name>`` lower-case
    inside the brackets, ``keyword`` lower-case; any other keyword is reported)."""

    label: str
    keyword: str
    count: Optional[Value]
    column: int
    end_column: int
    count_span: Optional[Span] = None


class _Empty:
    """A line with nothing to do: blank, comments only, or a lone line number."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "EMPTY"


EMPTY = _Empty()

Node = Union[CodeLine, KeywordLine, Assignment, BlockLine, _Empty]
