"""The motion-script language: text → command objects that carry their source position.

Strategy: each line is parsed alone (a regex fast path for the plain shape, else one Lark LALR
parser built from grammars/armctl.lark), then executed against the modal state into the frozen
command dataclasses of armctl/core/protocol.py.  Everything streams: a million-line script compiles
in flat memory.  Errors never raise: they are collected as located ``Diagnostic``s, all of them.

Modules, one job each:
  source.py          SourceSpan, Diagnostic (render() → ruff-style text), RULES (code table)
  grammar.py         loads the grammar, builds line nodes with transformer= (nodes.py)
  syntax_errors.py   Lark's UnexpectedInput → a plain sentence and a column
  fastpath.py        the regex fast path (must agree with grammar.py)
  expressions.py     #<name>, [expr]: nodes and evaluation
  modal.py           InitialState, ModalState (what is known between lines)
  statements.py      the G-code table: words → protocol command fields
  blocks.py          O<label> repeat … endrepeat pairing and body buffering
  compiler.py        Compilation: the streaming driver (lines, blocks, diagnostics)
  execute.py         how each statement runs against the modal state (moves, arcs, keywords)
  statement.py       Statement: a command object and its source position
  messages.py        the wording of the compiler's diagnostics
  files.py           reading a script once, bounded, into an immutable snapshot (UTF-8, line cap)

Usage::

    from armctl.script import compile_file, InitialState

    job = compile_file("job.txt", InitialState(speed_mm_min=3000), from_line=1)
    for statement in job:                # a stream of Statement
        frame = statement.command.encode()
        print(statement.line, statement.code, frame.hex())
    for diagnostic in job.diagnostics:   # complete once iteration ends
        print(diagnostic.render())
    job.raise_for_errors()               # ScriptError if there were errors
"""

from .compiler import DEFAULT_MAX_DIAGNOSTICS, MAX_LINE_LENGTH, Compilation, check_lines, compile_lines, compile_text
from .files import CutLine, ScriptSnapshot, compile_file, iter_lines, read_lines, read_script
from .modal import InitialState, ModalState
from .source import ERROR, RULES, WARNING, Diagnostic, Rule, SourceSpan
from .statement import Statement

__all__ = [
    "Compilation", "Diagnostic", "InitialState", "ModalState", "Rule", "RULES", "SourceSpan", "Statement",
    "check_lines", "compile_file", "compile_lines", "compile_text", "iter_lines", "read_lines", "read_script",
    "CutLine", "ScriptSnapshot",
    "DEFAULT_MAX_DIAGNOSTICS", "MAX_LINE_LENGTH", "ERROR", "WARNING",
]
