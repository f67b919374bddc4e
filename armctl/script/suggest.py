""""Did you mean …?" for script typos: statements, codes and words.

Strategy: a suggestion is offered only when it is *checked*, never guessed from spelling
alone.  A misspelt keyword (``PASUE``) is matched against the language's keywords with
difflib.  A line that does not parse is repaired in a few ways people actually slip — a letter
typed for a digit that looks like it (``O``→0, ``l``/``I``→1 in ``X25O``, ``Gl``) in the word at
the error or the one before it, and a bare number after a code that takes exactly one word
(``G4 500`` → ``G4 P500``) — and a repair is suggested only if the repaired line parses.
This runs only on the error path (a few extra parses of one line), never on good lines.
"""

from __future__ import annotations

import difflib
import re
from typing import Callable, Iterator, Optional

# keyword statements as written (armctl/script/execute.py's table, the names joined)
KEYWORD_STATEMENTS = ("RESET", "RESET CONNECTOR", "PAUSE", "POSE", "PROGRAM", "MODE")
# characters typed for the digit they look like
_LOOKALIKE_DIGITS = str.maketrans({"O": "0", "o": "0", "l": "1", "I": "1", "i": "1"})
_RUN = re.compile(r"[A-Za-z][A-Za-z0-9.]*")
_BARE_NUMBER_AFTER_CODE = re.compile(r"^(\s*[Gg])([0-9]+)(\s+)([+-]?[0-9.]+)\b")


def keyword(written: str) -> Optional[str]:
    """The keyword statement ``written`` is closest to (``PASUE`` → ``PAUSE``), or None."""
    words = written.upper().split()

    def likeness(name: str) -> float:  # word by word: RESET FOO is neither RESET nor RESET CONNECTOR
        names = name.split()
        if len(names) != len(words):
            return 0.0
        return min(difflib.SequenceMatcher(None, word, known).ratio() for word, known in zip(words, names))

    best = max(KEYWORD_STATEMENTS, key=likeness)
    return best if likeness(best) >= 0.6 else None


def repaired_line(text: str, column: int, parses: Callable[[str], bool],
                  single_word: Callable[[int], Optional[str]]) -> Optional[str]:
    """The first repair of ``text`` (which does not parse; ``column`` 1-based where the parser
    stopped) that ``parses``; ``single_word(g_number)`` is the one letter that G code takes,
    if it takes exactly one.  What changed, as the user would write it (``X250``, ``G4 P500``),
    or None."""
    for candidate, shown in _repairs(text, column, single_word):
        if candidate != text and parses(candidate):
            return shown
    return None


def _repairs(text: str, column: int, single_word) -> Iterator[tuple[str, str]]:
    """(the repaired line, the repaired part) in the order they are tried."""
    runs = [m for m in _RUN.finditer(text) if m.start() < column]  # the runs up to the error
    for match in reversed(runs[-2:]):  # the word at the error, then the one before it
        head, tail = match.group()[0], match.group()[1:]
        if head.upper() in ("G", "M", "N", "X", "Y", "Z", "A", "B", "C", "U", "V", "S", "T", "F", "P", "R", "K", "Q", "H"):
            fixed = tail.translate(_LOOKALIKE_DIGITS)
            if fixed != tail and re.fullmatch(r"[0-9.]+", fixed):
                yield text[:match.start()] + head + fixed + text[match.end():], head.upper() + fixed
    bare = _BARE_NUMBER_AFTER_CODE.match(text)
    if bare:
        letter = single_word(int(bare.group(2)))
        if letter is not None:
            yield (text[:bare.start(4)] + letter + text[bare.start(4):],
                   f"G{bare.group(2)} {letter}{bare.group(4)}")


def did_you_mean(suggestion: Optional[str]) -> str:
    """`` (did you mean PAUSE?)``, or nothing."""
    return f" (did you mean {suggestion}?)" if suggestion else ""
