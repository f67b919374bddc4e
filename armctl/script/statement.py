"""The compiler's product: one frame's command object and where in the script it came from.

Strategy: an immutable record that a consumer (run, estimate, lint, compile) can hold without
holding the compiler: the protocol command, the source position of the statement's head and
its whole line, the words as written, G90/G91, and the loop iteration it ran in.  A
``NamedTuple`` rather than a frozen dataclass because a million-line job builds a million of
them and a frozen dataclass is four times slower to construct; ``span`` and ``word_span`` build
``SourceSpan``s on demand.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping, NamedTuple, Optional

from ..core.protocol import Command
from .grammar import parse_line
from .source import SourceSpan

NO_WORDS: Mapping[str, float] = MappingProxyType({})


class Statement(NamedTuple):
    """One frame's command and where it came from (immutable).

    ``line`` is the 1-based source line and ``column``/``end_column`` the statement's head (its
    G/M code or keyword) on it; ``text`` is the whole line; ``span`` puts these together as a
    ``SourceSpan``.  ``code`` is the statement normalised (``'G1'``, ``'RESET CONNECTOR'``);
    ``words`` the words as written (letter → evaluated number, before G91 offsets);
    ``relative`` whether G91 was in effect; ``loop`` the 0-based iteration of each enclosing
    repeat block, outermost first.
    """

    command: Command
    file: str
    line: int
    column: int
    end_column: int
    text: str
    code: str
    words: Mapping[str, float] = NO_WORDS
    relative: bool = False
    loop: tuple[int, ...] = ()

    @property
    def span(self) -> SourceSpan:
        return SourceSpan(self.file, self.line, self.column, self.end_column, self.text)

    def word_span(self, letter: str) -> Optional[SourceSpan]:
        """Where the word ``letter`` (``'X'``, ``'J1'``) is written on this line, if it is."""
        node = parse_line(self.text)
        for (name, _), (column, end) in zip(getattr(node, "words", ()), getattr(node, "spans", None) or ()):
            if name == letter:
                return SourceSpan(self.file, self.line, column, end, self.text)
        return None
