"""A move with expression words takes ``_move``'s hot path when nothing is wrong (issue 13), and
the hot path says exactly what ``_move_with_diagnostics`` — the path that reports — says.

The slow reference is the same compiler with ``_move`` sending every line with word columns
to ``_move_with_diagnostics`` (as before the hot path took expression words); Hypothesis
writes scripts of assignments and moves whose words are parameters and expressions, with the
faults that matter to the choice: undefined and poisoned parameters, division by zero, values
out of a frame's range, a word twice, a word the statement does not take, G91, arcs, G6.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.script import compile_lines
from armctl.script.execute import StatementExecution
from armctl.script.grammar import parse_line

_move = StatementExecution._move


def _slow_move(self, number, text, node, spec, loop):
    if node.spans is None:
        return _move(self, number, text, node, spec, loop)  # literal words: not what this test is about
    return self._move_with_diagnostics(number, text, node, spec, loop)


def _compiled(lines):
    compilation = compile_lines(iter(lines), "expr.txt")
    statements = [(s.command, s.line, s.column, s.end_column, s.code, dict(s.words), s.relative, s.loop)
                  for s in compilation]
    diagnostics = [(d.span.line, d.span.column, d.span.end_column, d.code, d.message, d.hint)
                   for d in compilation.diagnostics]
    state = compilation.state
    return statements, diagnostics, dict(state.values), dict(state.parameters), dict(state.unknown_because)


def _both(lines):
    fast = _compiled(lines)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(StatementExecution, "_move", _slow_move)
        slow = _compiled(lines)
    return fast, slow


_NAME = st.sampled_from(["a", "b", "c", "B", "nope"])
_VALUE = st.one_of(
    st.sampled_from(["0", "1.5", "-2", "250", "1e3", "100000000000000000000000000000000000000000"]),
    _NAME.map(lambda name: f"#<{name}>"),
)
_EXPRESSION = st.one_of(
    _VALUE,
    st.tuples(_VALUE, st.sampled_from(["+", "-", "*", "/"]), _VALUE).map(lambda t: f"[{t[0]} {t[1]} {t[2]}]"),
    _VALUE.map(lambda value: f"-{value}"),
)
_LETTER = st.sampled_from(["X", "Y", "Z", "A", "F", "S", "T", "J1=", "R", "Q"])


@st.composite
def _line(draw):
    kind = draw(st.sampled_from(["assign", "assign", "move", "move", "move", "mode", "other"]))
    if kind == "assign":
        return f"#<{draw(_NAME)}> = {draw(_EXPRESSION)}"
    if kind == "mode":
        return draw(st.sampled_from(["G90", "G91"]))
    if kind == "other":
        return draw(st.sampled_from(["G6 J1=0 J2=0 J3=0 J4=0 J5=0 J6=0 F30", "G300 X200 Y10 Z150 R20",
                                     "G301 X210 Y0 Z150", "G1 X250 Y0 Z150 A180 B0 C0 F3000 S1000 (plain)"]))
    code = draw(st.sampled_from(["G1", "G1", "G1", "G301", "G300", "G6", "G4", "G54"]))
    words = draw(st.lists(st.tuples(_LETTER, _EXPRESSION), min_size=1, max_size=4))
    return code + " " + " ".join(f"{letter}{value}" for letter, value in words) + draw(
        st.sampled_from(["", " (step)", " ; done"]))


_START = ["#<a> = 200", "#<b> = 10", "#<c> = 150", "G1 X#<a> Y#<b> Z#<c> A180 B0 C0 F3000 S1000"]


@settings(max_examples=300, deadline=None)
@given(st.lists(_line(), max_size=12))
def test_expression_moves_compile_as_the_reporting_path_compiles_them(lines):
    fast, slow = _both(_START + lines)
    assert fast == slow


def test_expression_moves_known_script():
    lines = _START + ["G1 X[#<a> + 0.5] Y#<b> Z[#<c> - 0.5] (step 4)", "G91", "G1 X[#<c> / 100] Y-#<c>", "G90",
                      "#<b> = [#<b> / 0]", "G1 X[#<a> / 0]", "G1 X#<nope>", "G1 S[#<a> * 1000]", "G1 Z#<a> Z#<a>"]
    fast, slow = _both(lines)
    assert fast == slow
    statements, diagnostics = fast[0], fast[1]
    assert [s[1] for s in statements] == [4, 5, 7]  # the moves that build; the others are reported
    assert {d[3] for d in diagnostics} >= {"E009", "E003", "E005"}
    assert parse_line(lines[4]).spans is not None  # expression words carry their columns
