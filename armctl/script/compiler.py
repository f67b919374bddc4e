"""Compile a motion script as a stream: lines in, located command objects out.

Strategy: ``Compilation`` reads its lines one at a time and keeps nothing of a line once it is
done with it, so memory stays flat however long the script is.  Each line is parsed once —
by the regex fast path (armctl/script/fastpath.py) when it has the plain shape, else by Lark
(armctl/script/grammar.py) — then executed against the modal state (armctl/script/execute.py,
the other half of this class): the statement table (armctl/script/statements.py) turns words
into a protocol command, whose constructor is the one judge of ranges.  A line that executes
cleanly yields a ``Statement``; a line with errors yields nothing, adds located
``Diagnostic``s (all of them, for every line) and the compiler moves on.  Values a failed line tried to set are ``POISONED`` so the same mistake is not
reported again on every later line.

Lines with something to report are always re-parsed by Lark, which knows every word's
columns; the fast path never has to.  Repeat blocks are paired above the grammar
(armctl/script/blocks.py): the body of the outermost open block is buffered as parsed lines
and run when it closes (armctl/script/repeats.py, the base class ``RepeatExpansion``).  A G300 is held back until its G301 arrives, so that a broken pair
never yields half an arc.  With ``from_line``, earlier lines run for their modal state only.

Expansion is bounded: one script may run at most ``MAX_LINES_RUN`` lines, each pass of a
repeat block counted — its body lines and its endrepeat, once per pass, and its repeat line
once (a line sends at most one frame; an empty body still costs its passes).  Before a repeat
block runs, the lines it would run are counted from its text (count × one pass, nested counts
evaluated now), so ``O1 repeat [1e9]`` or 64 nested ``repeat [2]`` is one located E012 at
once, in time proportional to the text; a count only known as the block runs is still
caught by the running total.  Either way compiling stops there: nothing past it is run.

For checking only (``skip_repeats=True``, what lint asks for) — and in every compilation once
the script has an error, since nothing it yields can then be written or sent (``compile``, ``run``
and ``estimate`` refuse it: only diagnostics are left to find, and lint finds them this way, so
``compile`` of an unclosed ``repeat [999990]`` is as fast as lint's refusal) — a repeat block stops running
once a pass yields the same commands as the pass before it and ends in the same modal state:
the next pass starts where this one did, so it and every later one would yield exactly those
commands again and have nothing new to say (a pass with a PAUSE toggle is never cut short: the
pause state alternates).  A loop of absolute moves then costs two or three passes, whatever
its count; a G91 loop, whose targets move on, still runs each pass.  Compiling to send, such a
pass is not cut short but run again from its statements (armctl/script/repeats.py): the same
statements, to the bit, without executing its lines once per pass.
"""

from __future__ import annotations

from typing import Iterable, Iterator, Optional

from ..errors import ScriptError
from . import messages
from .blocks import BlockCollector, Line, Problem
from .execute import NOT_PLAIN, StatementExecution
from .fastpath import match_code_line, match_empty_line, node_from_scan, parse_expression_line, scanned_parts
from .grammar import parse_line
from .modal import InitialState, ModalState
from .nodes import EMPTY, BlockLine
from .repeats import RepeatExpansion
from .source import MAX_LINES_RUN, Diagnostic, SourceSpan
from .statement import Statement
from .syntax_errors import LineSyntaxError

MAX_LINE_LENGTH = 4096  # characters; longer lines are not statements (E011)
DEFAULT_MAX_DIAGNOSTICS = 1000  # kept in memory; later ones are only counted
_ABORT = object()  # _is_text: stop reading, the input is not text


class _TooLarge(Exception):
    """Raised (after E012 is reported) to stop compiling a script that expands too far."""


class Compilation(RepeatExpansion, StatementExecution):
    """One pass over a script: iterate it (once) for ``Statement``s; afterwards
    ``diagnostics`` (sorted by position), ``error_count``, ``ok`` and ``state`` are final.

    ``initial`` seeds the modal state (default: everything unknown).  Lines before
    ``from_line`` run for their modal state but yield nothing.  At most ``max_diagnostics``
    are kept (``error_count`` still counts every error; past the cap, an error inside a repeat
    body may count once per iteration).  ``fast=False`` parses every line with Lark (for tests
    and comparisons).  Statements of lines with errors are never yielded, but statements of
    good lines are, even when other lines have errors: a caller that must not act on a script
    with errors (``run``) compiles it to the end first, or buffers.
    """

    def __init__(
        self, lines: Iterable[str], file: str = "<script>", initial: InitialState | None = None, *,
        from_line: int = 1, max_diagnostics: int = DEFAULT_MAX_DIAGNOSTICS, fast: bool = True,
        skip_repeats: bool = False,
    ) -> None:
        if from_line < 1:
            raise ValueError(f"from_line counts from 1, not {from_line}")
        self.file = file
        self.from_line = from_line
        self.state = ModalState(initial)
        self.diagnostics: list[Diagnostic] = []
        self.error_count = 0
        self.lines_read = 0
        self.finished = False
        self._lines = lines
        self._fast = fast
        self._skip_repeats = skip_repeats
        self._max_diagnostics = max_diagnostics
        self._seen: set = set()
        self._blocks = BlockCollector()
        self._out: list[Statement] = []
        self._arc = None  # a held-back G300: its Statement, or its SourceSpan if it failed
        self._resume_text = ""
        self._started = False
        self._repeating = False  # running a repeat body again (not its first iteration)
        self.lines_run = 0  # every pass of a repeat block counted; at most MAX_LINES_RUN
        # skip_repeats: (the commands of a pass that repeated itself, how many more passes it
        # stands for), appended when the block stops early, before the next statement is yielded,
        # so a checker can count what the skipped passes would have done (lint's motion time)
        self.skipped_passes: list[tuple[list, int]] = []

    # --- public ---------------------------------------------------------------------------

    def __iter__(self) -> Iterator[Statement]:
        if self._started:
            raise RuntimeError("a Compilation can be iterated only once")
        self._started = True
        return self._run()

    @property
    def ok(self) -> bool:
        """True once the whole script was read without errors."""
        return self.finished and self.error_count == 0

    def finish(self) -> list[Diagnostic]:
        """Compile to the end (dropping the statements) and return the diagnostics; after a
        complete iteration, just return them."""
        for _ in self if not self._started else ():
            pass
        return self.diagnostics

    def raise_for_errors(self) -> None:
        """Raise ``ScriptError`` holding the diagnostics if the script has errors."""
        if self.error_count:
            raise ScriptError(self.diagnostics)

    # --- the line loop ----------------------------------------------------------------------

    def _run(self) -> Iterator[Statement]:
        try:
            yield from self._read()
        except _TooLarge:
            pass  # E012 is reported where it happened; nothing after it is run
        self.diagnostics.sort(key=lambda d: (d.span.line, d.span.column))
        self.finished = True

    def _read(self) -> Iterator[Statement]:
        fast = self._fast
        out, open_blocks, from_line, plain_move = self._out, self._blocks.stack, self.from_line, self._plain_move
        number = 0
        for number, raw in enumerate(self._lines, 1):
            text = raw.rstrip("\r\n")
            if number == from_line:
                self._resume_text = text
            if len(text) > MAX_LINE_LENGTH or not text.isascii() or "\x00" in text:
                verdict = self._is_text(number, text, getattr(raw, "length", len(text)))
                if verdict is _ABORT:
                    break
                if not verdict:
                    continue
            match = match_code_line(text) if fast else None
            counted = False  # lines_run already counts this line (the hot path below)
            if match is not None and not open_blocks:  # the hot path: a plain G line, no node built
                counted = True
                self.lines_run += 1
                if self.lines_run > MAX_LINES_RUN:
                    self._too_large(number, text)
                statement = plain_move(number, text, match)
                if statement is not NOT_PLAIN:
                    if statement is not None:
                        yield statement
                    elif out:
                        yield from out
                        out.clear()
                    continue
            if match is not None:
                scanned = scanned_parts(match)
            else:  # as scan(text) says, without matching the code line twice
                scanned = EMPTY if fast and match_empty_line(text) else None
            if scanned is None:
                node = self._parse(number, text)
                if node is None or node is EMPTY:
                    continue
            elif scanned is EMPTY:
                continue
            else:
                node = node_from_scan(scanned)
            if open_blocks or type(node) is BlockLine:
                yield from self._block_line(Line(number, text, node))
                continue
            if not counted:  # a plain line the hot path handed on (G91, an unknown value) is one line
                self.lines_run += 1
                if self.lines_run > MAX_LINES_RUN:
                    self._too_large(number, text)
            self._execute(number, text, node, ())
            if out:
                yield from out
                out.clear()
        else:
            self.lines_read = number
            yield from self._end_of_file()
        self.lines_read = number

    def _too_large(self, number: int, text: str, column: int = 1, end_column: int | None = None, message: str | None = None):
        self._report("E012", number, text, column, len(text) + 1 if end_column is None else end_column,
                     message or f"the script runs more than {MAX_LINES_RUN:,} lines by this line "
                                "(every pass of a repeat block counted)",
                     "a script this long is surely generated by mistake; split the job or lower the repeat counts")
        raise _TooLarge

    def _is_text(self, number: int, text: str, length: int):
        """False (and E011) for a line too long to be a statement or not valid UTF-8;
        ``_ABORT`` (and E011) for a NUL byte: the input is binary, reading stops.  Checked
        before either parser, so the fast path and Lark see the same lines.  ``length`` is the
        line's real length in characters (a cut line is shorter than the line was)."""
        if "\x00" in text:
            column = text.index("\x00") + 1
            self._report("E011", number, text, column, column + 1,
                         "NUL byte: this looks like a binary file, not a motion script",
                         "armctl reads motion scripts as UTF-8 text; reading stopped here")
            return _ABORT
        if len(text) > MAX_LINE_LENGTH:
            self._report("E011", number, text, MAX_LINE_LENGTH + 1, len(text) + 1,
                         f"line is {length} characters long; a statement has at most {MAX_LINE_LENGTH}")
            return False
        try:
            text.encode("utf-8")
        except UnicodeEncodeError as error:
            self._report("E011", number, text, error.start + 1, error.start + 2, messages.not_utf8(text[error.start]),
                         "save the script as UTF-8")
            return False
        return True

    def _parse(self, number: int, text: str):
        if self._fast:  # expression words and assignments, without Lark when they are plain enough
            node = parse_expression_line(text)
            if node is not None:
                return node
        try:
            return parse_line(text)
        except LineSyntaxError as error:
            self._report(error.code, number, text, error.column, error.end_column, error.message, error.hint)
            return None

    def _end_of_file(self) -> Iterator[Statement]:
        problems: list[Problem] = []
        block = self._blocks.close_all(self.lines_read, problems)
        self._report_problems(problems)
        if block is not None:
            yield from self._run_block(block, ())
        if self._arc is not None:
            span = self._arc.span if isinstance(self._arc, Statement) else self._arc
            self._report_at(span, "E006", "G300 must be followed directly by G301", "the file ends after it")
        self._arc = None
        if self.from_line > max(self.lines_read, 1):
            self._report_resume(f"the file has {self.lines_read} line{'' if self.lines_read == 1 else 's'}", None)

    # --- diagnostics ------------------------------------------------------------------------

    def _report(self, code, number, text, column, end_column, message, hint=None) -> None:
        self._report_at(SourceSpan(self.file, number, column, end_column, text), code, message, hint)

    def _report_at(self, span: SourceSpan, code: str, message: str, hint: Optional[str] = None) -> None:
        # Once is enough for the same mistake met again: the same message at the same place,
        # or — in a later iteration of a repeat block, where values may differ — the same
        # code at the same place.
        place = (span.line, span.column, code)
        if (place, message) in self._seen or (self._repeating and place in self._seen):
            return
        diagnostic = Diagnostic.of(code, span, message, hint)
        if diagnostic.is_error:
            self.error_count += 1
        if len(self.diagnostics) < self._max_diagnostics:
            self._seen.update(((place, message), place))
            self.diagnostics.append(diagnostic)

    def _report_problems(self, problems: list[Problem]) -> None:
        for problem in problems:
            self._report("E008", problem.line.number, problem.line.text, problem.column, problem.end_column,
                         problem.message, problem.hint)

    def _report_resume(self, why: str, hint: Optional[str]) -> None:
        self._report("E010", self.from_line, self._resume_text, 1, 1, f"cannot resume at line {self.from_line}: {why}", hint)


def compile_lines(
    lines: Iterable[str], file: str = "<script>", initial: InitialState | None = None, *,
    from_line: int = 1, max_diagnostics: int = DEFAULT_MAX_DIAGNOSTICS, fast: bool = True, skip_repeats: bool = False,
) -> Compilation:
    """Compile ``lines`` (an open text file, a list of strings …) as a stream; see ``Compilation``."""
    return Compilation(lines, file, initial, from_line=from_line, max_diagnostics=max_diagnostics, fast=fast,
                       skip_repeats=skip_repeats)


def compile_text(text: str, file: str = "<script>", initial: InitialState | None = None, **options) -> Compilation:
    """Compile a whole script held in a string."""
    return compile_lines(text.splitlines(), file, initial, **options)


def check_lines(lines: Iterable[str], file: str = "<script>", initial: InitialState | None = None, **options) -> list[Diagnostic]:
    """Every diagnostic for a script (its statements are compiled and dropped)."""
    return compile_lines(lines, file, initial, **options).finish()
