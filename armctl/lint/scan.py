"""What lint learns from the source text itself, as the compiler reads it line by line.

Strategy: ``LineScanner.watch(lines)`` sits between the file and the compiler and hands every
line on unchanged, so the file is still read once and never held.  On the way it notes what
statements cannot tell: which parameters are assigned and which are read (L401 unused), and
the count of each repeat block (L402 a count of 0, which the language accepts).  A count is
evaluated with the language itself (a one-line compilation of ``#<probe> = count``) using the
parameters the compiler holds at that moment — exact for a block outside any other block,
since the compiler has executed every earlier line when it asks for the next one; nested
blocks are judged only when their count is a literal (their parameters change per pass).

It also notes NUL and undecodable bytes and over-long lines — the compiler's fast path
accepts comment lines without looking at their bytes, and plain lines whatever their length,
but a file that is not UTF-8 text deserves E011 wherever the byte is (the engine drops the
note when the compiler reported the line itself).

Memory: one entry per distinct parameter name, whatever the length of the script.  Also here:
``ignored_codes(text)``, the parser of the inline ``; armctl: ignore[CODE, …]`` comment.
"""

from __future__ import annotations

import re
from typing import Callable, Iterable, Iterator, Mapping, Optional

from ..script import MAX_LINE_LENGTH, InitialState, SourceSpan, compile_lines

_PARAMETER = re.compile(r"#<([A-Za-z_][A-Za-z0-9_]*)>")
# a parameter (group 1, in a lower-cased ASCII line) or what code_text blanks: a "(…)" comment
# up to the first ")", or the rest of the line from a ";" (group 1 empty for those)
_PARAMETER_OR_COMMENT = re.compile(r"\([^)]*\)|;.*|#<([a-z_][a-z0-9_]*)>", re.S)
_ASSIGNMENT = re.compile(r"\s*(?:[Nn][0-9]+\s*)?#<([A-Za-z_][A-Za-z0-9_]*)>\s*=")
# A repeat line as the grammar reads it (grammars/armctl.lark: LINE_NUMBER, LABEL, NAME), in a
# line whose comments code_text blanked: the one rule, for lint and for the resume line
# (``block_line``).  Compiled on first use (re's cache): only a line with an O needs it, and
# compiling it cost every start-up 0.5 ms.
_BLOCK = r"\s*(?:[Nn][0-9]+\s*)?[Oo](?:<[A-Za-z0-9_]+>|[0-9]+)\s*(repeat|endrepeat)\b\s*(.*?)\s*$"
# Searched from just after the line's first ";" only: every later ";" finds the same first match,
# and trying the pattern at each of them (``;.*?armctl…``) was quadratic in the number of ";".
_IGNORE = re.compile(r"\barmctl:\s*ignore\b(?:\[([^\]]*)\])?", re.I)
_PROBE = "armctl_lint_repeat_count"
_MAX_NOT_TEXT = 100  # E011 findings kept from the scanner per file

Finding = tuple[str, SourceSpan, str, Optional[str]]  # code, span, message, hint


def ignored_codes(text: str) -> Optional[tuple[str, ...]]:
    """The codes (or prefixes, upper case) an inline ``; armctl: ignore[…]`` silences on this
    line; ``()`` for a bare ``; armctl: ignore`` (everything); None without the comment."""
    comment = text.find(";")
    if comment < 0 or "armctl" not in text.lower():
        return None
    match = _IGNORE.search(text, comment + 1)
    if match is None:
        return None
    if match.group(1) is None:
        return ()
    return tuple(code.strip().upper() for code in re.split(r"[,\s]+", match.group(1)) if code.strip())


def block_line(text: str) -> Optional[re.Match]:
    """The repeat or endrepeat of a script line (group 1, any case; group 2 the count's text),
    comments and all as the compiler reads it; None for any other line."""
    if "o" not in text and "O" not in text:
        return None
    code = code_text(text)
    if "o" not in code and "O" not in code:
        return None
    return re.match(_BLOCK, code, re.I)


def code_text(text: str) -> str:
    """The line with comments blanked out (same length up to the ``;``, so columns hold): a
    ``(…)`` comment runs to the first ``)``; an unclosed ``(`` stays (the compiler reports it).
    One left-to-right scan: linear in the line's length, whatever it holds."""
    if "(" not in text:
        return text.split(";", 1)[0]
    parts, position = [], 0
    while (start := text.find("(", position)) >= 0:
        end = text.find(")", start)
        if end < 0:
            break
        parts += [text[position:start], " " * (end + 1 - start)]
        position = end + 1
    parts.append(text[position:])
    return "".join(parts).split(";", 1)[0]


class LineScanner:
    """Watches one script's lines on their way to the compiler (see the module docstring)."""

    def __init__(self, file: str, parameters: Callable[[], Mapping[str, object]], report: Callable[..., None]) -> None:
        self.file = file
        self._parameters = parameters  # the compiler's live parameter values
        self._report = report  # report(code, span, message, hint): L402 as soon as it is found
        self._defined: dict[str, SourceSpan] = {}  # name (lower) → first assignment
        self._used: set[str] = set()
        self._depth = 0
        self.first_line = ""
        self.lines = 0
        self.not_text: list[Finding] = []  # E011 candidates (comments the compiler skips), bounded

    def watch(self, lines: Iterable[str]) -> Iterator[str]:
        number = self.lines
        defined, note_read = self._defined, self._used.update
        for raw in lines:
            number += 1
            self.lines = number
            if number == 1:
                self.first_line = raw.rstrip("\r\n")
            text_ok = raw.isascii()
            if not text_ok or "\x00" in raw or len(raw) > MAX_LINE_LENGTH:
                self._not_text(number, raw.rstrip("\r\n"))
            if "#" in raw:
                if text_ok:
                    # _parameters_in for an ASCII line (nearly every line), inline (issue 13: this
                    # bookkeeping was ~5 µs of lint's own ~14 µs a line of expressions): one
                    # regular expression over the lower-cased line steps over comments as
                    # code_text blanks them, without building the blanked copy; the names come
                    # out lower case, "" for each comment.  Lower-casing keeps every column of an
                    # ASCII line, so the names and their order are those _parameters_in finds
                    # (tests/test_lint_scan.py holds the two together).
                    found = _PARAMETER_OR_COMMENT.findall(raw.lower())
                    # an assignment's target is the first parameter of the line's code; a match on
                    # the raw line holds no comment (the pattern has no "(" or ";"): it is one on its code
                    if "=" in raw and (_ASSIGNMENT.match(raw) is not None
                                       or ("(" in raw and _ASSIGNMENT.match(code_text(raw)) is not None)):
                        first = 0  # the target: the first name (only comments, "", can come before it)
                        while not found[first]:
                            first += 1
                        if found[first] not in defined:
                            self._define(number, raw.rstrip("\r\n"), found[first])
                        found = found[first + 1:]
                    note_read(found)  # "" (a comment) is never a name: unused_parameters asks for names only
                else:
                    text = raw.rstrip("\r\n")
                    self._parameters_in(number, text, code_text(text))
            if "o" in raw or "O" in raw:
                self._look(number, raw.rstrip("\r\n"))
            yield raw

    def _not_text(self, number: int, text: str) -> None:
        """NUL bytes and undecodable bytes (lone surrogates) anywhere on the line, comments too."""
        if len(self.not_text) >= _MAX_NOT_TEXT:
            return
        if len(text) > MAX_LINE_LENGTH:  # read_lines cut it: the compiler's fast path may not see it
            span = SourceSpan(self.file, number, MAX_LINE_LENGTH + 1, len(text) + 1, text)
            self.not_text.append(("E011", span, f"line is longer than {MAX_LINE_LENGTH} characters: not a statement",
                                  "is this file a motion script?"))
            return
        nul = text.find("\x00")
        bad = next((k for k, c in enumerate(text) if 0xDC80 <= ord(c) <= 0xDCFF), -1)
        if nul >= 0 and (bad < 0 or nul < bad):
            span = SourceSpan(self.file, number, nul + 1, nul + 2, text)
            self.not_text.append(("E011", span, "NUL byte: this looks like a binary file, not a motion script",
                                  "armctl reads motion scripts as UTF-8 text"))
        elif bad >= 0:
            span = SourceSpan(self.file, number, bad + 1, bad + 2, text)
            self.not_text.append(("E011", span, f"byte 0x{ord(text[bad]) - 0xDC00:02x} is not UTF-8 text",
                                  "save the script as UTF-8"))

    def _look(self, number: int, text: str) -> None:
        block = block_line(text)
        if block is not None:
            self._block(number, text, block)

    def _define(self, number: int, text: str, name: str) -> None:
        """The first assignment of ``name`` (lower case): the line's first parameter."""
        match = _PARAMETER.search(code_text(text))
        self._defined[name] = SourceSpan(self.file, number, match.start() + 1, match.end() + 1, text)

    def _parameters_in(self, number: int, text: str, code: str) -> None:
        names = _PARAMETER.findall(code)
        if not names:
            return
        # An assignment's target is the line's first parameter (the pattern anchors at its start);
        # every other one is read.  Its columns are looked up only the first time it is assigned.
        if "=" in code and _ASSIGNMENT.match(code) is not None:
            target = names[0].lower()
            if target not in self._defined:
                match = _PARAMETER.search(code)
                self._defined[target] = SourceSpan(self.file, number, match.start() + 1, match.end() + 1, text)
            del names[0]
        self._used.update(name.lower() for name in names)

    def _block(self, number: int, text: str, block: re.Match) -> None:
        if block.group(1).lower() == "endrepeat":
            self._depth = max(self._depth - 1, 0)
            return
        depth, self._depth = self._depth, self._depth + 1
        expression = block.group(2)
        if not expression or (depth and "#" in expression):
            return
        if evaluate(expression, self._parameters()) == 0:
            span = SourceSpan(self.file, number, block.start(2) + 1, block.end(2) + 1, text)
            self._report("L402", span, f"repeat count {expression} is 0: the block never runs",
                         "remove the block, or give it a count of 1 or more")

    def unused_parameters(self) -> Iterator[Finding]:
        for name, span in self._defined.items():
            if name not in self._used:
                yield ("L401", span, f"#<{span.snippet[2:-1]}> is assigned but never read",
                       "check the spelling where it is used, or remove the assignment")


def evaluate(expression: str, parameters: Mapping[str, object]) -> Optional[float]:
    """The value of a count expression with these parameters, in the language's own arithmetic;
    None when it has no value (undefined parameter, syntax: the compiler reports those)."""
    known = {name: value for name, value in parameters.items() if type(value) is float}
    probe = compile_lines([f"#<{_PROBE}> = {expression}"], "<repeat count>", InitialState(parameters=known))
    probe.finish()
    value = probe.state.parameters.get(_PROBE)
    return value if type(value) is float else None
