"""The regex fast path and the lean resolver must agree with the full path they shortcut.

Differential tests on generated input: for every line, ``parse_fast`` either declines (None)
or returns exactly the node Lark builds — so the two agree on which lines they reject, since
the fast path rejects nothing itself; ``resolve_planned`` (one plan per line shape) either declines or returns exactly
what ``resolve`` does; and a whole compilation gives the same statements and diagnostics with
and without the fast path.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from armctl.errors import FieldError
from armctl.script import InitialState, compile_lines
from armctl.script.fastpath import _simple_line, parse_expression_line, parse_fast
from armctl.script.grammar import parse_line
from armctl.script.modal import POISONED, ModalState
from armctl.script.nodes import EMPTY
from armctl.script.statements import CODES, plain_plan, resolve, resolve_planned
from armctl.script.syntax_errors import LineSyntaxError

# --- generated lines ---------------------------------------------------------------------------

numbers = st.one_of(
    st.from_regex(r"\A[+-]?([0-9]{1,6}(\.[0-9]{0,4})?|\.[0-9]{1,4})\Z"),
    st.sampled_from(["0", "-0", "+.5", "5.", "007", "1e5", "1.2.3", "", "-", ".", "9" * 60]),
)
letters = st.sampled_from(list("XYZABCUVSTFKQHRPJNGMEOxyzsf") + ["J1=", "j6=", "J7=", "J0="])
words = st.builds(lambda letter, number: letter + number, letters, numbers)
codes = st.sampled_from(["G1", "g1", "G01", "G6", "G220", "G230", "G300", "G301", "G4", "G54", "G90", "G91", "G2", "M3",
                         "m117", "M", "G", "N10 G1", "n5G1", "G" + "1" * 12, "N10"])
gaps = st.sampled_from(["", " ", "  ", "\t", " (c) ", "(a;b)", " ( ", " ) ", " ;x", "é", "\x00", "$", " = "])
others = st.sampled_from(["X#<a>", "X[1+2]", "J1=#<a>", "RESET", "pose 2", "#<a> = 1", "O<a> repeat [2]", "[", "]",
                          "#", "(", ";", "\r", "\udcff", "X-#<a>", "X[", "POSE"])


@st.composite
def lines(draw):
    parts = [draw(st.sampled_from(["", " ", "\t"])), draw(codes)]
    for _ in range(draw(st.integers(0, 14))):
        parts.append(draw(gaps) if draw(st.integers(0, 4)) == 0 else " ")
        parts.append(draw(words) if draw(st.integers(0, 6)) else draw(others))
    if draw(st.booleans()):
        parts.append(draw(st.sampled_from([" ; comment", ";", " (tail)", "   ", " ; (", " ; é"])))
    return "".join(parts)


any_line = st.one_of(lines(), st.text(max_size=60), st.text(alphabet="GXYZJ1=0.5- ;()#<>[]\t", max_size=40))


def lark(line: str):
    try:
        return parse_line(line)
    except LineSyntaxError:
        return "rejected"


@settings(max_examples=700, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(any_line)
@example("G1 X10 Y-2.5 Z.5 A+3 B5. C0 F3000 S1500 ; c")
@example("N10G1X1Y2(c)Z3;x")
@example("G6 J1=5 j6=-.5")
@example("G6 J1=#<a>")
@example("G1 J7=1")
@example("G1 X1.2.3")
@example("G1 X5 (unclosed")
@example("  (c) ; nothing")
@example("G1 " + "X1 " * 13)
def test_fast_path_answers_only_what_lark_answers_the_same_way(line):
    fast = parse_fast(line)
    if fast is not None:
        assert lark(line) == fast


@settings(max_examples=150, deadline=None)
@given(st.lists(st.sampled_from([
    "G1 X10 Y20 Z30 A0 B0 C0", "G1 X1", "g1 x-2.5 F100", "G1 T2 S2000", "G1 T3 X1", "G1 S9999", "G1 F0", "G1 X1 X2",
    "G6 J1=10 J2=0 J3=0 J4=0 J5=0 J6=0", "G6 J1=5 H7", "G220 X1 K100", "G230 X1 Q5", "G300 X1 R5", "G301 X2",
    "G4 P100", "G4 P-1", "G54 X0 Y0 Z0", "G90", "G91", "M3", "RESET", "POSE 1", "#<a> = [#<a> + 1]", "G1 X#<a>",
    "G1 Q5", "G1 X1 ; c", "G1 (c) Y2", "N5 G1 Z3", "G1 X", "", "O<r> repeat [2]", "O<r> endrepeat", "G1 U5 V-5",
    "G1 X[#<a> * 2] Y-#<a>", "#<a> = [#<a> / 0]", "G1 X[1/0]", "#<b> = -#<a>", "G1 X#<b>", "G1 S[#<a> * 9999]",
]), max_size=25))
def test_compiling_with_and_without_the_fast_path_is_the_same(script):
    initial = InitialState(pose=(0, 0, 0, 0, 0, 0), pwm_us={1: 1500}, speed_mm_min=100, accel_mm_s2=10,
                           parameters={"a": 1})
    fast = compile_lines(script, "t.txt", initial)
    slow = compile_lines(script, "t.txt", initial, fast=False)
    assert list(fast) == list(slow)
    assert fast.diagnostics == slow.diagnostics


# --- the lean resolver -------------------------------------------------------------------------

state_values = st.one_of(st.none(), st.just(POISONED), st.floats(-1000, 1000), st.sampled_from([1.0, 2.0, 3.0, 4.0]))
written_values = st.one_of(st.floats(-1000, 1000), st.sampled_from([1.0, 2.0, 4.0, 5.0, 2.5, 0.0]))


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(sorted(CODES)), st.data())
def test_resolve_planned_agrees_with_resolve(number, data):
    spec = CODES[number]
    state = ModalState()
    for key in state.values:
        state.values[key] = data.draw(state_values, label=key) if key != "T" else data.draw(
            st.sampled_from([1.0, 2.0, 3.0, 4.0, POISONED]), label="T")
    letters = data.draw(st.lists(st.sampled_from(spec.letters), unique=True), label="letters")
    written = {letter: data.draw(written_values, label=letter) for letter in letters}
    full = resolve(spec, written, state)
    plan = plain_plan(spec, tuple(written))
    if plan is None:  # the general path judges this shape
        return
    plain = resolve_planned(plan, list(written.values()), state.values)
    assert (plain is not None) == full.ok
    if plain is not None:
        assert plain == (full.arguments, full.updates)
        # the hot path calls plan.run on the scanned words (number strings): resolve(), then the
        # protocol constructor — the same command, or the same FieldError, as spec.make
        words = tuple(item for letter, value in written.items() for item in (letter, repr(value)))
        assert plan.arguments(words, state.values) == (tuple(full.arguments), full.updates, written)
        try:
            expected = spec.make(*full.arguments)
        except FieldError as error:
            with pytest.raises(FieldError, match=re.escape(str(error))):
                plan.run(words, state.values)
        else:
            command, updates, words_written = plan.run(words, state.values)
            assert (type(command), command, updates, words_written) == (type(expected), expected, full.updates, written)
    else:
        assert plan.run(tuple(item for pair in written.items() for item in pair), state.values) is None


def test_a_plan_covers_the_common_shapes():
    """The hot path plans every shape a generated job writes (else the test above proves little)."""
    for letters in (("X", "Y", "Z"), ("X", "Y", "Z", "A", "B", "C", "F", "S"), ("S", "F"), ()):
        assert plain_plan(CODES[1], letters) is not None
    assert plain_plan(CODES[6], ("J1", "J2", "S", "H")) is not None
    assert plain_plan(CODES[1], ("T", "X")) is None and plain_plan(CODES[1], ("J1",)) is None


def test_fast_path_examples():
    assert parse_fast("G1 X1 (c) Y2 ; z").words == (("X", 1.0), ("Y", 2.0))
    assert parse_fast("; nothing") is EMPTY
    assert parse_fast("G1 X#<a>") is None  # expressions go to Lark
    assert parse_fast("RESET") is None


# --- the expression fast path ------------------------------------------------------------------

GOOD_SPACES = ["", "", " ", "  ", "\t", " (c) ", "(x)"]
BAD_SPACES = [" ( ", ";", " ; c", "é", "\x00", ")"]
GOOD_ATOMS = ["#<a>", "#<A_1>", "#<b>", "5.", "0", "12.5", ".5"]
BAD_ATOMS = ["#<>", "#<1a>", "#a", "1.2.3", "1e5", "X", "", "[", "]"]


def expressions(space, atom, depth: int = 2):
    """Expression text with spaces and comments anywhere."""
    if depth == 0:
        return atom
    inner = st.deferred(lambda: expressions(space, atom, depth - 1))
    return st.one_of(
        atom,
        st.builds(lambda s, v: s + v, st.sampled_from(["-", "+", "--", "- ", "-+"]), inner),
        st.builds(lambda a, s1, op, s2, b: a + s1 + op + s2 + b, inner, space, st.sampled_from("+-*/"), space, inner),
        st.builds(lambda s1, v, s2: "[" + s1 + v + s2 + "]", space, inner, space),
    )


@st.composite
def expression_lines(draw, bad: bool):
    """Code lines with expression words, and assignments: all well formed, or with some of
    their pieces drawn from malformed ones (``bad``)."""
    def pick(good, wrong):
        return st.one_of(st.sampled_from(good), st.sampled_from(good), st.sampled_from(wrong)) if bad else \
            st.sampled_from(good)

    space = pick(GOOD_SPACES, BAD_SPACES)
    atom = st.one_of(st.from_regex(r"\A([0-9]{1,4}(\.[0-9]{0,3})?|\.[0-9]{1,3})\Z"), pick(GOOD_ATOMS, BAD_ATOMS))
    value = st.one_of(st.builds(lambda v: "[" + v + "]", expressions(space, atom)), atom,
                      st.builds(lambda s, v: s + v, st.sampled_from(["-", "+", "--", "-+"]), atom),
                      st.builds(lambda s, v: s + "[" + v + "]", st.sampled_from(["-", "+"]), expressions(space, atom, 1)))
    head = draw(pick(["G1", "g1", "G01", "M3", "N5 G1", "n5G1", " G1", "#<a>", "#<A_1>", "N2 #<b>", "G1X1"],
                     ["(c) G1", "G", "#<a", "RESET", "O<r> repeat", "#<a> ="]))
    parts = [head]
    if "#" in head:
        parts += [draw(space), draw(pick(["="], ["", "=="])), draw(space), draw(value)]
    else:
        for _ in range(draw(st.integers(0, 6))):
            parts.append(draw(space) or " ")
            letter = draw(pick(list("XYZABCSFxK") + ["J1=", "j6="], ["J7=", "JX", "1"]))
            if draw(st.integers(0, 3)):
                parts.append(letter + draw(pick(["", "", "-", "+"], [" ", "--"])) + draw(value))
            else:
                parts.append(letter + draw(st.from_regex(r"\A[+-]?([0-9]{1,4}(\.[0-9]{0,3})?|\.[0-9]{1,3})\Z")))
    parts.append(draw(pick(["", " ; end", " (tail)"], [" ]", "[", " X"])))
    return "".join(parts)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(expression_lines(bad=False), expression_lines(bad=True), any_line))
@example("G1 X[#<a>+1] Y#<b> Z10 ; c")
@example("#<a> = [#<a> * 0.5 + -1]")
@example("G1 J1=#<a> J2=[2]")
@example("G1 X[" * 60 + "1" + "]" * 60)
@example("G1 X[" + "1+" * 120 + "1]")
@example("G1 X[" + "-" * 200 + "#<a>]")
@example("G1 X[[" + "1+" * 60 + "1]" + "+1" * 60 + "]")  # brackets keep the depth of what they hold
@example("#<a> = [1 / 2 * 3 - 4 / -#<b>]")
def test_expression_fast_path_answers_only_what_lark_answers_the_same_way(line):
    """Whenever it answers, the node is Lark's, word columns and expression columns included."""
    fast = parse_expression_line(line)
    if fast is not None:
        slow = lark(line)
        assert slow == fast
        assert repr(slow) == repr(fast)  # every column of every expression node
        assert getattr(slow, "spans", None) == getattr(fast, "spans", None)


def test_expression_fast_path_reads_the_common_shapes():
    """It answers for the lines it exists for (else the test above proves little)."""
    for line in ("#<z> = 150", "G1 X[200 + 20] Y0 Z#<z> A180 F3000", "G1 X-#<a> J1=[#<a> * 2] ; c", "N3 #<a> = -[1]",
                 "#<a> = [#<a> + 1]", "G1 X[1 / 2 * #<a>] Y[-1 - -2]"):
        assert parse_expression_line(line) is not None, line
    for line in ("RESET", "O<r> repeat [2]", "#<a> = 1 + 2", "G1 X[1", "G1 X[" + "1+" * 120 + "1]"):
        assert parse_expression_line(line) is None, line


# --- the common expression shapes (fastpath._simple_line), read a word at a time ---------------

SIMPLE_SPACES = ["", "", " ", "  ", "\t"]
SIMPLE_ATOMS = ["#<a>", "#<X_1>", "5.", "0", "12.5", ".5", "-3", "-.5", "-0"]


@st.composite
def simple_lines(draw, bad: bool):
    """Lines of the shapes _simple_line reads (literal, #<name> or [atom op atom] words, and
    ``#<name> = value``), and with ``bad`` near misses: a sign or comment where it declines,
    a second operator, a broken token, something left at the end."""
    def pick(good, wrong):
        return st.one_of(st.sampled_from(good), st.sampled_from(good), st.sampled_from(wrong)) if bad else \
            st.sampled_from(good)

    space = pick(SIMPLE_SPACES, ["(c)", " ; c", "é", "\x00"])
    # legal operands the reader leaves to the general one (other signs, nesting) drawn as often
    # as its own, so that a reader taking one of them wrongly is caught
    declined = ["--1", "+1", "+.5", "- 1", "-#<a>", "+#<a>", "[1]", "[#<a> + 1]"]
    atom = st.one_of(st.sampled_from(SIMPLE_ATOMS), st.sampled_from(declined if bad else SIMPLE_ATOMS),
                     pick(SIMPLE_ATOMS, ["#<1a>", "1.2.3", "1e5", "", "-", "1 2"]))
    operator = pick(list("+-*/"), ["", "++", "+ 1 +", "=", "%"])

    def value():
        kind = draw(st.integers(0, 2))
        if kind == 0:
            return draw(pick(["#<a>", "#<B>", "#<_c9>"], ["-#<a>", "+#<a>", "#<a", "[#<a>]"]))
        if kind == 1:
            return draw(st.from_regex(r"\A-?([0-9]{1,4}(\.[0-9]{0,3})?|\.[0-9]{1,3})\Z"))
        return ("[" + draw(space) + draw(atom) + draw(space) + draw(operator) + draw(space) + draw(atom)
                + draw(space) + draw(pick(["]"], ["", "]]", ")"])))

    head = draw(pick(["G1", "g1", "G01", "M3", "N5 G1", "n5G1", " G1", "G1 (c)", "#<a>", "#<A_1>", "N2 #<b>",
                      "\t#<x>"], ["(c) G1", "G", "#<a", "RESET", "#<a> =", "O<r> repeat"]))
    parts = [head]
    if head.lstrip().startswith(("#", "N2 #")):
        parts += [draw(pick(SIMPLE_SPACES + [" (c) "], [";"])), draw(pick(["="], ["", "=="])), draw(space), value()]
    else:
        for _ in range(draw(st.integers(0, 7))):
            parts.append(draw(pick(["", " ", "  ", " (c) ", "\t"], ["(", ")"])))
            letter = draw(pick(list("XYZABCSFxK") + ["J1=", "j6=", "J2"], ["J7=", "JX", "1", "#"]))
            parts.append(letter + (draw(st.from_regex(r"\A[+-]?([0-9]{1,4}(\.[0-9]{0,3})?|\.[0-9]{1,3})\Z"))
                                   if draw(st.integers(0, 3)) == 0 else value()))
    parts.append(draw(pick(["", " ; end", " (tail)", "(a)(b) ;c", "  "], [" ]", "[", " X", " (", "=1"])))
    return "".join(parts)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(simple_lines(bad=False), simple_lines(bad=True)))
@example("G1 X[#<x> + 0.5] Y#<y> Z[#<z> - 0.5] (step 6)")
@example("#<y> = [#<y> + -14.63]")
@example("#<a> = -0 ; c")
@example("N5 G1 J1=[-1*#<a>]X1 j6=#<B>")
@example("G1 X[5 -- 3]")
@example("G1 X[#<a> -5]")
@example("G1 X[+1 * 2] Y[#<a> - +.5]")
@example("G1" + " X[#<a> + 1]" * 20)
def test_common_shape_reader_answers_only_what_lark_answers_the_same_way(line):
    """The word-at-a-time reader in front of the general one: whenever it answers, the node is
    Lark's, every column included; whatever it declines, the general reader still may read."""
    fast = _simple_line(line)
    if fast is not None:
        slow = lark(line)
        assert slow == fast
        assert repr(slow) == repr(fast)
        assert slow.spans == fast.spans if hasattr(slow, "spans") else slow.value_span == fast.value_span


def test_common_shape_reader_reads_the_benchmark_shapes():
    """It answers for the lines it exists for (benchmarks/cli_speed.py's), and declines the
    shapes it leaves to the general reader."""
    for line in ("#<x> = 220", "#<y> = [#<y> + -14.63]", "G1 X#<x> Y#<y> Z#<z> A180 B0 C0 F6000 S1000",
                 "G1 X[#<x> + 0.5] Y#<y> Z[#<z> - 0.5] (step 6)", "G1 X[200 + 20] Y0 Z#<z> A180 B0 C0 F3000 S1000"):
        assert _simple_line(line) is not None, line
    for line in ("G1 X[1 + 2 + 3]", "G1 X-#<a>", "G1 X[(c)1 + 2]", "#<a> = +1", "G1 X[[1] + 2]", "G1 X[#<a>]"):
        assert _simple_line(line) is None, line
        assert parse_expression_line(line) == lark(line), line  # the general reader still answers
