"""Repeat blocks as they run: each pass of a block's buffered lines, bounded, and cut short when checking.

Strategy: ``RepeatExpansion`` is the part of ``Compilation`` (armctl/script/compiler.py) that
runs a closed repeat block (paired above the grammar by armctl/script/blocks.py): the body's
parsed lines are executed once per pass (armctl/script/execute.py), nested blocks inside, every
pass counted against ``MAX_LINES_RUN``.  Before a block runs, the lines it would run are counted
from its text (``_check_expansion``: count × one pass, nested counts evaluated now), so an
absurd count is one E012 at once.  When checking only (``skip_repeats``, or once the script has
an error) a block stops as soon as a pass yields the same commands as the one before and ends
in the same modal state: every later pass would repeat it (compiler.py's docstring says why).
When compiling to send, the same argument, made to the bit (``_Pass``), runs such a block's
later passes from the statements of the one that repeated — its pass number changed, its lines
counted — instead of executing its lines again; a pass longer than ``MAX_PASS_KEPT`` statements
is not kept, so memory stays flat, and a block whose passes keep differing (a G91 loop) stops
keeping them after ``MAX_PASS_MISSES``, so it costs what it did.

Contract with the host class: it provides ``state``, ``from_line``, ``error_count``, ``_out``,
``_blocks``, ``_skip_repeats``, ``_repeating``, ``lines_run``, ``skipped_passes``,
``_execute``, ``_interrupt_arc``, ``_too_large`` and the reporters ``_report``,
``_report_problems`` and ``_report_resume``.
"""

from __future__ import annotations

import math
from typing import Iterator, Optional

from ..core.protocol import PauseToggle
from .blocks import Block, Line, Problem
from .expressions import ExpressionError, Unavailable, evaluate, format_value
from .nodes import BlockLine
from .source import MAX_LINES_RUN
from .statement import Statement

MAX_PASS_KEPT = 4096  # statements of one pass kept to run it again (``_Pass``): memory stays flat
MAX_PASS_MISSES = 3  # passes of a block that differed from the one before, before its passes are no longer kept
_new_statement = tuple.__new__  # a Statement (a NamedTuple) from all its fields


class RepeatExpansion:
    """Runs repeat blocks (see the module docstring for what the host class provides)."""

    def _block_line(self, line: Line) -> Iterator[Statement]:
        node, blocks, problems = line.node, self._blocks, []
        complete = None
        if type(node) is not BlockLine:
            blocks.add(line)
        elif node.keyword == "repeat":
            if node.count is None:
                problems.append(Problem(line, node.column, node.end_column, f"{node.label} repeat needs a count",
                                        f"write {node.label} repeat [n]"))
            blocks.open(line, problems)
        elif node.keyword == "endrepeat":
            complete = blocks.close(line, problems)
        else:
            problems.append(Problem(line, node.column, node.end_column,
                                    f"{node.label} {node.keyword} is not supported: only repeat and endrepeat",
                                    f"blocks are {node.label} repeat [n] … {node.label} endrepeat"))
        self._report_problems(problems)
        if complete is not None:
            yield from self._run_block(complete, ())

    def _run_block(self, block: Block, path: tuple) -> Iterator[Statement]:
        if not path and block.line < self.from_line <= block.end_line:
            self._report_resume(f"it is inside {block.label} repeat (lines {block.line}–{block.end_line})",
                                f"resume at line {block.line} or after line {block.end_line}")
        self._interrupt_arc(block.line, f"{block.label} repeat")
        self._count_line(block.opening)  # the repeat line runs once
        count = self._count(block)
        if count:
            self._check_expansion(block, count)
        repeating = self._repeating
        previous = None  # (the commands of the last pass, the modal state it ended with)
        last = None  # running: the last pass, while the passes may repeat it (``_Pass``)
        keep = MAX_PASS_KEPT > 0  # running: passes are kept until MAX_PASS_MISSES differed from the one before
        misses = 0
        count = count or 0
        index = 0
        while index < count:
            if last is not None and last.repeated and self.lines_run + last.lines <= MAX_LINES_RUN:
                yield from last.again(self, path, index)  # the same pass run again (see the docstring)
                index += 1
                continue
            loop = path + (index,)
            self._repeating = repeating or index > 0
            lines_before = self.lines_run
            self._count_line(block.opening)  # the pass itself (its endrepeat), even with an empty body
            commands = [] if self._skip_repeats or self.error_count else None  # checking only (see the docstring)
            # running: kept while the pass is short and another pass may repeat it
            statements = [] if commands is None and keep and index + 1 < count else None
            for statement in self._pass(block, loop):
                if commands is not None:
                    commands.append(statement.command)
                elif statements is not None:
                    statements.append(statement)
                    if len(statements) > MAX_PASS_KEPT:
                        statements = None
                yield statement
            self._interrupt_arc(block.end_line, f"{block.label} endrepeat")
            if commands is not None:
                current = (commands, self._fingerprint())
                if current == previous and not any(type(c) is PauseToggle for c in commands):
                    # every later pass would yield these same commands again (see the docstring)
                    if index + 1 < count:
                        self.skipped_passes.append((commands, count - index - 1))
                    break
                previous = current
            before, last = last, None if statements is None or self.error_count else _Pass(
                statements, len(path), self.lines_run - lines_before, self._fingerprint, last)
            if before is not None and last is not None and last._state is None:
                misses += 1  # (a G91 loop's passes all differ: it stops paying for keeping them)
                keep = misses < MAX_PASS_MISSES
            index += 1
        self._repeating = repeating

    def _pass(self, block: Block, loop: tuple) -> Iterator[Statement]:
        out = self._out
        for item in block.items:
            if type(item) is Block:
                yield from self._run_block(item, loop)
                continue
            self._count_line(item)
            self._execute(item.number, item.text, item.node, loop)
            if out:
                yield from out
                out.clear()

    def _fingerprint(self) -> tuple:
        """The modal state as plain, comparable data (what the next pass starts from)."""
        state = self.state
        return (tuple(state.values.items()), tuple(sorted(state.parameters.items())), state.relative)

    def _count_line(self, line: Line) -> None:
        self.lines_run += 1
        if self.lines_run > MAX_LINES_RUN:
            self._too_large(line.number, line.text)

    def _check_expansion(self, block: Block, count: int) -> None:
        """E012 at the repeat line, before it runs, if ``count`` passes would run more lines
        than the script has left (counted from the text: see ``_pass_lines``)."""
        room = MAX_LINES_RUN - self.lines_run
        per_pass = self._pass_lines(block, room)
        if per_pass is not None and count * per_pass > room:
            line = block.opening
            self._too_large(line.number, line.text, *line.node.count_span,
                            f"{block.label} repeat would run {count:,} passes × {per_pass:,} lines; one script runs at "
                            f"most {MAX_LINES_RUN:,} lines (every pass of a repeat block counted)")

    def _pass_lines(self, block: Block, room: int) -> Optional[int]:
        """Lines one pass of ``block`` runs (as ``_run_block`` counts them: the pass, each body
        line, each nested block's repeat line and passes, with nested counts as they evaluate
        now); None when a nested count is not known yet (the running total still bounds it).
        Stops counting past ``room``: the answer is then "too many"."""
        total = 1
        for item in block.items:
            total += 1
            if type(item) is Block and not item.too_deep and item.count is not None:
                try:
                    count = evaluate(item.count, self.state.parameters)
                except (ExpressionError, Unavailable):
                    return None
                if math.isfinite(count) and count >= 1 and count == int(count):  # else it never runs
                    inner = self._pass_lines(item, room)
                    if inner is None:
                        return None
                    total += int(count) * inner
            if total > room:
                return total
        return total

    def _count(self, block: Block) -> Optional[int]:
        node, line = block.opening.node, block.opening
        if node.count is None or block.too_deep:  # reported when the block opened
            return None
        try:
            value = evaluate(node.count, self.state.parameters)
        except ExpressionError as error:
            self._report(error.code, line.number, line.text, error.column, error.end_column, error.message, error.hint)
            return None
        except Unavailable:
            return None
        if not (math.isfinite(value) and value >= 0 and value == int(value)):
            self._report("E008", line.number, line.text, *node.count_span,
                         f"a repeat count must be a whole number >= 0, not {format_value(value)}")
            return None
        return int(value)


class _Pass:
    """One pass of a repeat block as it ran — its statements, the lines it counted — and whether
    it ran exactly as the pass before it (``repeated``): the same statements to the bit (all but
    their own pass number), no PAUSE (the arm's pause state alternates), ending in the same modal
    state to the bit.  Then every later pass starts where this one did and would run it again,
    so ``again`` yields its statements with the pass number changed instead of executing its
    lines: a block of absolute moves is compiled once or twice, whatever its count (issue 23).
    Bits, not ``==``: 0.0 equals -0.0, but a frame holding the one is not the other."""

    __slots__ = ("statements", "commands", "depth", "lines", "_state", "_before", "_repeated")

    def __init__(self, statements: list, depth: int, lines: int, fingerprint, before: "_Pass | None") -> None:
        self.statements, self.depth, self.lines = statements, depth, lines
        self.commands = [s.command for s in statements]
        # the modal state is read only after a pass that yielded what the one before did (a G91
        # loop's passes never do: they pay for no fingerprint), so a repeat is seen a pass later at worst
        same = before is not None and before.lines == lines and before.commands == self.commands
        self._state = fingerprint() if same else None
        # equal by ==: the bits are compared only if a pass is left to run (``repeated``)
        self._before = before if same and before._state is not None and before._state == self._state else None
        self._repeated = None
        if before is not None:
            before._before = None  # each pass keeps at most the one before it

    @property
    def repeated(self) -> bool:
        if self._repeated is None:
            before, self._before = self._before, None
            self._repeated = before is not None and not any(type(c) is PauseToggle for c in self.commands) and (
                repr(before._state) == repr(self._state) and before._bits() == self._bits())
        return self._repeated

    def _bits(self) -> str:
        depth = self.depth
        return repr([(s[:-1], s.loop[depth + 1:]) for s in self.statements])

    def again(self, compilation, path: tuple, index: int) -> Iterator[Statement]:
        """Pass ``index`` of the block: this pass's statements, numbered ``index`` (nested passes kept)."""
        compilation._repeating = True
        compilation.lines_run += self.lines
        depth, loop = self.depth, path + (index,)
        for statement in self.statements:
            inner = statement.loop[depth + 1:]
            yield _new_statement(Statement, statement[:-1] + ((loop + inner) if inner else loop,))
