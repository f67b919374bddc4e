"""Where a diagnostic points, what it says, and the one table of diagnostic codes.

Strategy: a diagnostic is plain data — a ``SourceSpan`` (file, 1-based line and columns, the
source line itself) plus a stable code, a severity, a sentence and an optional hint — so lint,
compile, run and estimate can format it as they like (``render()`` gives ruff-style text,
``as_dict()`` the fields for JSON).  ``RULES`` maps every code the language can emit to its
severity and a one-line rationale; ``armctl lint --list-rules`` prints it.

Columns count characters (a tab is one column) and ``end_column`` is exclusive, like Lark's
tokens: the span ``X10`` at column 4 has ``end_column`` 7.  Rendering keeps tabs in the caret
line so the caret stays under its character, and shows control characters and undecodable
bytes as visible stand-ins so a diagnostic can always be printed.
"""

from __future__ import annotations

from typing import NamedTuple

from ..core.records import record

ERROR = "error"
WARNING = "warning"


class Rule(NamedTuple):
    severity: str
    summary: str


# What one script may expand to (E012).  Lines run, every pass of a repeat block counted
# (a line sends at most one frame): twice the 1,000,000-line benchmark script, more than a day
# of frames at the line's 20 frames/s.  Motion time, by the profile's model (armctl/core/estimate.py):
# a job longer than a day is surely a mistake (G4 P is milliseconds; U/V are degrees).
MAX_LINES_RUN = 2_000_000
MAX_JOB_MOTION_S = 24 * 3600.0

# code → (severity, one-line rationale).  Codes are stable: tools and CI configs refer to them.
RULES: dict[str, Rule] = {
    "E001": Rule(ERROR, "syntax: the line does not read as a statement (a word without its number, a stray character, an unclosed comment or bracket)"),
    "E002": Rule(ERROR, "unknown statement or word: a G/M code, keyword or letter the language does not have, or a word the statement does not take"),
    "E003": Rule(ERROR, "duplicate word: a letter may appear once per line"),
    "E004": Rule(ERROR, "missing value: a move needs a value nobody wrote (an unknown modal value, a word required on every line, or a G91 offset from an unknown value)"),
    "E005": Rule(ERROR, "out of range: the value cannot be sent in a frame (protocol limits, whole numbers, 32-bit floats)"),
    "E006": Rule(ERROR, "arc pairing: a G300 must be followed directly by its G301, and a G301 needs its G300"),
    "E007": Rule(ERROR, "undefined parameter: #<name> is used before any assignment gives it a value"),
    "E008": Rule(ERROR, "repeat structure: O<label> repeat / endrepeat must pair up with the same label and a whole count >= 0"),
    "E009": Rule(ERROR, "arithmetic: division by zero or a result too large for a number"),
    "E010": Rule(ERROR, "resume line: a --from-line must start at a statement outside repeat blocks and arcs, within the file"),
    "E011": Rule(ERROR, "not text: the line is not valid UTF-8, contains NUL bytes, or is too long to be a statement"),
    "E012": Rule(ERROR, f"too large: the script would run more than {MAX_LINES_RUN:,} lines (every pass of a repeat "
                        f"block counted) or more than {MAX_JOB_MOTION_S / 3600:g} hours of motion"),
}


@record(slots=True)
class SourceSpan:
    """A run of characters on one source line.

    ``line`` and ``column`` are 1-based; ``end_column`` is exclusive (the column just after the
    span, equal to ``column`` for a point such as "the end of the line"); ``text`` is the
    whole source line without its line ending.
    """

    file: str
    line: int
    column: int
    end_column: int
    text: str

    @property
    def snippet(self) -> str:
        """The characters the span covers."""
        return self.text[self.column - 1 : self.end_column - 1]


@record(slots=True)
class Diagnostic:
    """One finding about a script: where, which code, how bad, what, and how to fix it."""

    span: SourceSpan
    code: str
    severity: str
    message: str
    hint: str | None = None

    @classmethod
    def of(cls, code: str, span: SourceSpan, message: str, hint: str | None = None) -> "Diagnostic":
        """A diagnostic with the severity ``RULES`` gives its code."""
        return cls(span, code, RULES[code].severity, message, hint)

    @property
    def is_error(self) -> bool:
        return self.severity == ERROR

    @property
    def location(self) -> str:
        return f"{self.span.file}:{self.span.line}:{self.span.column}"

    def __str__(self) -> str:
        return f"{self.location}: {self.code} {self.message}"

    def render(self, max_width: int = 100) -> str:
        """Ruff-style text: the headline, the source line, a caret under the span, the hint."""
        gutter = str(self.span.line)
        pad = " " * len(gutter)
        source, caret = _source_and_caret(self.span, max_width)
        lines = [str(self), f"{pad} |", f"{gutter} | {source}", f"{pad} | {caret}"]
        if self.hint:
            lines += [f"{pad} |", f"{pad} = hint: {_printable(self.hint)}"]
        return "\n".join(lines)

    def as_dict(self) -> dict:
        """The fields as plain data (for JSON output)."""
        return {
            "file": self.span.file, "line": self.span.line, "column": self.span.column,
            "end_column": self.span.end_column, "code": self.code, "severity": self.severity,
            "message": self.message, "hint": self.hint,
        }


def _printable(text: str) -> str:
    """Control characters and lone surrogates (undecodable bytes) as one visible character each,
    so columns still line up and the text can be encoded for any terminal."""
    out = []
    for char in text:
        code = ord(char)
        if char == "\t":
            out.append(char)
        elif code < 0x20 or code == 0x7F or 0x80 <= code < 0xA0 or 0xD800 <= code <= 0xDFFF:
            out.append("\ufffd")
        else:
            out.append(char)
    return "".join(out)


def _source_and_caret(span: SourceSpan, max_width: int) -> tuple[str, str]:
    """The (possibly elided) source line and the caret line under it."""
    text = span.text
    start = max(span.column - 1, 0)
    width = max(span.end_column - span.column, 1)
    offset = 0
    if len(text) > max_width:  # show a window around the span
        offset = max(0, min(start - max_width // 3, len(text) - max_width))
        shown = text[offset : offset + max_width]
        prefix = "…" if offset else ""
        suffix = "…" if offset + max_width < len(text) else ""
        text = prefix + shown + suffix
        start = start - offset + len(prefix)
        width = min(width, max_width - (start - len(prefix)) + 1)
    lead = "".join("\t" if c == "\t" else " " for c in text[:start]).ljust(start)
    return _printable(text).rstrip(), lead + "^" * max(width, 1)
