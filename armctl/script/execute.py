"""How each statement runs against the modal state: moves, arcs, keywords, parameters.

Strategy: ``StatementExecution`` is the half of ``Compilation`` (armctl/script/compiler.py)
that gives statements their meaning; the other half reads lines and keeps the diagnostics,
and armctl/script/repeats.py runs repeat blocks.  Moves take one of three paths, each starting from the same untouched state:

  1. ``_plain_move`` — the hot path: a line the regex fast path scanned, in absolute mode,
     with every value known (``resolve_planned``: one plan per line shape, compiled once); no node is built.
  2. ``_move`` — any other node (a fast-path line in a repeat body, or G91; a line with
     expression words): in absolute mode it runs its shape's plan as path 1 does (expression
     words evaluated first); else the general ``resolve``; at the first sign of trouble the
     line takes path 3 (re-parsed with Lark if it has no word columns).
  3. ``_move_with_diagnostics`` — a Lark node with columns: report everything wrong with the
     line, commit what it did set, poison what it failed to set (armctl/script/move_diagnostics.py,
     the base class ``MoveDiagnostics``).

A G300 is held back (``_arc``) until its G301 arrives; anything else in between is reported
and the half arc dropped, so no half arc is ever yielded.

Contract with the host class: it provides ``state``, ``file``, ``from_line``, ``_out`` (a
list of statements to yield), ``_arc`` and the reporters ``_report``, ``_report_at`` and
``_report_resume``.
"""

from __future__ import annotations

import math
from typing import Optional

from ..errors import FieldError
from ..core.protocol import GoToPose, MCode, PauseToggle, ResetArm, ResetConnector, RunProgram, StructureMode
from . import messages
from .expressions import POISONED, ExpressionError, Unavailable, evaluate, format_value
from .grammar import LETTERS, parse_line
from .modal import CARTESIAN, JOINTS, UNKNOWN
from .move_diagnostics import MoveDiagnostics
from .nodes import Assignment, CodeLine, KeywordLine
from .source import SourceSpan
from .suggest import did_you_mean
from .suggest import keyword as keyword_like
from .statement import NO_WORDS, Statement
from .statements import CODES, DISTANCE_MODES, MoveSpec, PlainPlan, plain_plan, resolve

NOT_PLAIN = object()  # _plain_move: take the general path
_new_statement = tuple.__new__  # _moved builds a Statement (a NamedTuple) from all its fields

_KEYWORDS = {  # names → (command, what the number is or None, families it leaves unknown)
    ("RESET",): (ResetArm, None, (CARTESIAN, JOINTS)),
    ("RESET", "CONNECTOR"): (ResetConnector, None, ()),
    ("PAUSE",): (PauseToggle, None, ()),
    ("POSE",): (GoToPose, "a fixed pose 0…3", (CARTESIAN, JOINTS)),
    ("PROGRAM",): (RunProgram, "an SD-card program 0…15", (CARTESIAN, JOINTS)),
    ("MODE",): (StructureMode, "structure mode 0 or 1", ()),
}


# The hot path's plans by line shape (code letter, digits, word letters as written): at most
# MAX_PLANS shapes are kept, so memory stays flat whatever a script writes.
MAX_PLANS = 4096
_PLANS: dict = {}
# Plans for moves with expression words, by (G number, canonical letters): see ``_move``.
_EXPRESSION_PLANS: dict = {}


def _plan(shape: tuple) -> Optional[PlainPlan]:
    """The plan for a scanned line's shape (``plain_plan``), None if it is not a known G code."""
    letter, digits, names = shape
    plan = None
    if letter in "Gg" and len(digits) <= 9:
        spec = CODES.get(int(digits))
        if spec is not None:
            plan = plain_plan(spec, tuple(LETTERS[name] for name in names))
    if len(_PLANS) < MAX_PLANS:
        _PLANS[shape] = plan
    return plan


class StatementExecution(MoveDiagnostics):
    """Runs one parsed line (see the module docstring for what the host class provides)."""

    def _execute(self, number: int, text: str, node, loop: tuple) -> None:
        """Run any parsed line but a block line; what it yields goes to ``_out``."""
        kind = type(node)
        if kind is CodeLine:
            if node.letter == "G":
                spec = CODES.get(node.number)
                if spec is not None:
                    statement = self._move(number, text, node, spec, loop)
                    if statement is not None:
                        self._out.append(statement)
                elif node.number in DISTANCE_MODES:
                    self._distance_mode(number, text, node)
                else:
                    self._interrupt_arc(number, node.code)
                    self._report("E002", number, text, node.column, node.end_column,
                                 f"unknown statement {text[node.column - 1:node.end_column - 1].upper()}",
                                 messages.unknown_g_code(node.number))
            else:
                self._m_code(number, text, node, loop)
        elif kind is KeywordLine:
            self._keyword(number, text, node, loop)
        elif kind is Assignment:
            self._assign(number, text, node)

    # --- moves (G1 G220 G222 G230 G6 G300 G301 G4 G54) -------------------------------------

    def _plain_move(self, number: int, text: str, match) -> Optional[Statement]:
        """The hot path: a G line the fast path's regex matched (``match``: see
        ``scanned_parts``), in absolute mode, with every value known.

        Returns the statement to yield (or None: held back or before ``from_line``), or
        ``NOT_PLAIN`` without having changed anything — then the line takes the general path."""
        state = self.state
        if state.relative:
            return NOT_PLAIN
        groups = match.groups()
        words = groups[2 : match.lastindex]
        shape = (groups[0], groups[1], words[::2])
        plan = _PLANS.get(shape, NOT_PLAIN)
        if plan is NOT_PLAIN:
            plan = _plan(shape)
        if plan is None:
            return NOT_PLAIN
        try:
            plain = plan.run(words, state.values)  # resolve(), then the protocol constructor
        except FieldError:
            return NOT_PLAIN
        if plain is None:
            return NOT_PLAIN
        return self._moved(plan.spec, plain[0], plain[1], number, text, match.start(1) + 1, match.end(2) + 1, plain[2], ())

    def _moved(self, spec: MoveSpec, command, updates: dict, number: int, text: str, column: int, end_column: int,
               written: dict, loop: tuple) -> Optional[Statement]:
        """A move that built: commit its state and hand its statement on (or hold an arc)."""
        state = self.state
        values = state.values
        values.update(updates)
        forgets = spec.forgets
        if forgets:
            values.update(UNKNOWN[forgets])
            state.unknown_because[forgets] = (spec.code, number)
        # every field given, in order: the tuple itself, without NamedTuple's Python-level __new__
        statement = _new_statement(Statement, (command, self.file, number, column, end_column, text, spec.code, written,
                                               state.relative, loop))
        if self._arc is None and not spec.is_arc:
            return statement if number >= self.from_line else None
        return self._sequence(spec.code, number, text, (column, end_column), statement)

    def _move(self, number: int, text: str, node: CodeLine, spec: MoveSpec, loop: tuple) -> Optional[Statement]:
        """Execute a move (or G4/G54); return its statement if it is to be yielded alone.

        The first half is the hot path: in absolute mode, a line with expression words whose
        values evaluate runs its shape's plan (as ``_plain_move``); else a line whose words all
        belong to the statement and whose command builds.  Anything else takes ``_move_with_diagnostics``,
        which starts again from the same, untouched state.  Arcs and failures return None
        (a completed arc pair goes to ``self._out``)."""
        words = node.words
        state = self.state
        if not state.relative:
            # absolute mode: the words' values (expression words evaluated now, issue 13), then the
            # line shape's plan as _plain_move runs it (resolve() and the constructor as straight-line
            # code) — a repeat body's plain lines come this way, once per pass; any doubt takes the
            # path below.  tests/test_script_expression_moves.py holds this to the reporting path,
            # tests/test_script_fastpath.py the plans to resolve()
            shape = (node.number, tuple([letter for letter, _ in words]))
            plan = _EXPRESSION_PLANS.get(shape, NOT_PLAIN)
            if plan is NOT_PLAIN:
                plan = plain_plan(spec, shape[1])
                if len(_EXPRESSION_PLANS) < MAX_PLANS:
                    _EXPRESSION_PLANS[shape] = plan
            if plan is not None:
                parameters, flat = state.parameters, []
                try:
                    for letter, value in words:
                        flat += (letter, value if value.__class__ is float else value.evaluate(parameters))
                    plain = plan.run(flat, state.values)
                except (ExpressionError, Unavailable, FieldError):
                    plain = None
                if plain is not None:
                    return self._moved(spec, plain[0], plain[1], number, text, node.column, node.end_column, plain[2],
                                       loop)
        written = dict(words)
        if len(written) == len(words) and written.keys() <= spec.letter_set:
            if node.spans is not None:  # expression words: their values now, or the path that reports why not
                parameters = self.state.parameters
                try:
                    written = {letter: evaluate(value, parameters) for letter, value in words}
                except (ExpressionError, Unavailable):
                    written = None
            if written is not None:
                resolution = resolve(spec, written, self.state)
                if resolution.ok:
                    try:
                        command = spec.make(*resolution.arguments)
                    except FieldError:
                        command = None
                    if command is not None:
                        return self._moved(spec, command, resolution.updates, number, text, node.column,
                                           node.end_column, written, loop)
        if node.spans is None:
            node = parse_line(text)
        return self._move_with_diagnostics(number, text, node, spec, loop)

    def _sequence(self, code: str, number: int, text: str, head: tuple[int, int], statement: Optional[Statement]):
        """Arc pairing for a move that just ran (``statement`` None if it failed): hold a G300
        back, pair a G301 with it, and report a G300 something else follows."""
        if code == "G300":
            if self._arc is not None:
                self._interrupt_arc(number, code)
            self._arc = statement if statement is not None else SourceSpan(self.file, number, *head, text)
            return None
        if code == "G301":
            arc, self._arc = self._arc, None
            if arc is None:
                self._report("E006", number, text, *head, "G301 has no G300 before it", messages.ARC_HINT)
            elif statement is not None:
                self._complete_arc(arc, statement)
            return None
        if self._arc is not None:
            self._interrupt_arc(number, code)
        if statement is not None and number >= self.from_line:
            return statement
        return None

    # --- the other statements ----------------------------------------------------------------

    def _distance_mode(self, number: int, text: str, node: CodeLine) -> None:
        self._interrupt_arc(number, node.code)
        if node.words:
            node = node if node.spans is not None else parse_line(text)
            for (letter, _), (column, end) in zip(node.words, node.spans):
                self._report("E002", number, text, column, end, f"unknown word '{letter}' in {node.code}",
                             f"{node.code} takes no words; put the move on the next line")
            return
        self.state.relative = DISTANCE_MODES[node.number]

    def _m_code(self, number: int, text: str, node: CodeLine, loop: tuple) -> None:
        self._interrupt_arc(number, "an M code")
        head = text[node.column - 1:node.end_column - 1].upper()
        if node.words:
            node = node if node.spans is not None else parse_line(text)
            for (letter, _), (column, end) in zip(node.words, node.spans):
                self._report("E002", number, text, column, end, f"unknown word '{letter}' in {head}",
                             "an M code is sent as its number alone")
            return
        try:
            command = MCode(node.number)
        except FieldError:
            self._report("E005", number, text, node.column, node.end_column,
                         f"{head} is outside the M-code range (a 32-bit signed integer)")
            return
        if number >= self.from_line:
            self._out.append(Statement(command, self.file, number, node.column, node.end_column, text,
                                       f"M{node.number}", NO_WORDS, self.state.relative, loop))

    def _keyword(self, number: int, text: str, node: KeywordLine, loop: tuple) -> None:
        keyword = node.keyword
        self._interrupt_arc(number, keyword)
        head = (node.column, node.end_column)
        entry = _KEYWORDS.get(node.names)
        if entry is None:
            written = text[node.column - 1:node.end_column - 1]
            self._report("E002", number, text, *head, f"unknown statement '{written}'{did_you_mean(keyword_like(written))}",
                         messages.STATEMENTS_HINT)
            return
        build, takes, forgets = entry
        argument = None
        if takes is None and node.argument is not None:
            self._report("E002", number, text, *node.argument_span, f"{keyword} takes no number")
            return
        for family in forgets:  # whatever happens next, the user meant the arm to move
            self.state.forget(family, (keyword, number))
        if takes is not None:
            if node.argument is None:
                self._report("E004", number, text, *head, f"{keyword} needs a number", f"write {keyword} n: {takes}")
                return
            try:
                argument = evaluate(node.argument, self.state.parameters)
            except ExpressionError as error:
                self._report(error.code, number, text, error.column, error.end_column, error.message, error.hint)
                return
            except Unavailable:
                return
        try:
            command = build(argument) if takes is not None else build()
        except FieldError as error:
            reason = str(error).split(" ", 1)[1] if " " in str(error) else str(error)
            self._report("E005", number, text, *node.argument_span, f"{keyword} {reason}", f"{keyword} takes {takes}")
            return
        if number >= self.from_line:
            self._out.append(Statement(command, self.file, number, *head, text, keyword, NO_WORDS,
                                       self.state.relative, loop))

    def _assign(self, number: int, text: str, node: Assignment) -> None:
        self._interrupt_arc(number, f"#<{node.name}> =")
        parameters = self.state.parameters
        try:
            value = evaluate(node.value, parameters)
        except ExpressionError as error:
            parameters[node.name] = POISONED
            self._report(error.code, number, text, error.column, error.end_column, error.message, error.hint)
            return
        except Unavailable:
            parameters[node.name] = POISONED
            return
        if not math.isfinite(value):
            parameters[node.name] = POISONED
            self._report("E009", number, text, *node.value_span, f"#<{node.name}> = {format_value(value)} is not a usable number")
            return
        parameters[node.name] = value

    # --- arcs -------------------------------------------------------------------------------

    def _interrupt_arc(self, number: int, what: str) -> None:
        """Something other than G301 comes next: a held-back G300 is reported and dropped."""
        arc, self._arc = self._arc, None
        if arc is not None:
            span = arc.span if isinstance(arc, Statement) else arc
            self._report_at(span, "E006", "G300 must be followed directly by G301", f"line {number} has {what}")

    def _complete_arc(self, arc, end: Statement) -> None:
        if not isinstance(arc, Statement):  # no G300 (reported) or a failed one (reported)
            return
        if arc.line < self.from_line <= end.line:
            self._report_resume(f"it is inside the arc G300 (line {arc.line}) … G301 (line {end.line})",
                                f"resume at line {arc.line}, the G300")
        elif arc.line >= self.from_line:
            self._out += (arc, end)
