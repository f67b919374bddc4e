"""Parameters, expressions and repeat blocks (LinuxCNC style), handled above the grammar."""

from __future__ import annotations

import pytest

from armctl.script import InitialState, compile_lines, compile_text
from armctl.script.expressions import Binary, Negate, Parameter
from armctl.script.grammar import parse_line
from armctl.script.nodes import Assignment, BlockLine, CodeLine

KNOWN = InitialState(
    pose=(100, 0, 50, 0, 0, 0), joints_deg=(0, 0, 0, 0, 0, 0), pwm_us={1: 1500}, speed_mm_min=3000,
    speed_deg_s=20, accel_mm_s2=500,
)


def run(source, initial=KNOWN, **options):
    job = compile_text(source, "t.txt", initial, **options)
    statements = list(job)
    return statements, [str(d) for d in job.diagnostics]


def xs(source, initial=KNOWN):
    statements, diagnostics = run(source, initial)
    assert diagnostics == []
    return [s.command.x_mm for s in statements]


# --- expressions ------------------------------------------------------------------------------


@pytest.mark.parametrize("expression, value", [
    ("5", 5), ("-5", -5), ("[5]", 5), ("[-5]", -5), ("[1 + 2 * 3]", 7), ("[[1 + 2] * 3]", 9),
    ("[10 - 4 - 3]", 3), ("[12 / 3 / 2]", 2), ("[-2 * -3]", 6), ("[- [1 + 1]]", -2), ("[2 * -#<a>]", -8),
    ("#<a>", 4), ("-#<a>", -4), ("[#<A> / 8]", 0.5), ("[ 1.5+.5 ]", 2), ("[+3]", 3), ("[1 - -1]", 2),
    ("[[[[1]]]]", 1), ("[#<a>*#<a>-#<a>]", 12),
])
def test_expression_values(expression, value):
    assert xs(f"#<a> = 4\nG1 X{expression}") == [value]


def test_assignment_values_and_case_insensitive_names():
    assert xs("#<Feed> = [2 * 50]\n#<feed> = [#<FEED> + 1]\nG1 X#<feed>") == [101]


def test_parameters_are_global_and_reassignable():
    assert xs("#<x> = 1\nG1 X#<x>\n#<x> = 2\nG1 X#<x>") == [1, 2]


def test_expressions_in_joint_words_and_keyword_arguments():
    statements, diagnostics = run("#<j> = 30\nG6 J1=#<j> J2=[#<j> / 2] J3=-#<j>")
    assert diagnostics == [] and statements[0].command.joints_deg[:3] == (30, 15, -30)


def test_parse_tree_is_made_of_located_nodes():
    node = parse_line("G1 X[#<a> + 2 * -#<b>]")
    assert isinstance(node, CodeLine) and node.spans == ((4, 23),)
    [(letter, value)] = node.words
    assert letter == "X"
    assert value == Binary("+", Parameter("a", 6, 10), Binary("*", 2.0, Negate(Parameter("b", 18, 22), 17, 22), 13, 22), 6, 22)
    assert parse_line("#<A> = -5") == Assignment("a", -5.0, 1, 10, (8, 10))
    assert parse_line("O<Loop> REPEAT [3]") == BlockLine("O<loop>", "repeat", 3.0, 1, 19, (16, 19))


def test_undefined_parameter():
    _, diagnostics = run("G1 X#<y>\n#<b> = [#<c> + 1]\nG1 X#<b>")
    assert diagnostics == [
        "t.txt:1:5: E007 parameter #<y> is not defined",
        "t.txt:2:9: E007 parameter #<c> is not defined",  # line 3 depends on it: not repeated
    ]


def test_numbers_too_large_for_arithmetic():
    big = "9" * 300
    _, diagnostics = run(f"#<a> = [{big} * {big}]")
    assert diagnostics == [f"t.txt:1:9: E009 [{float(big)!r} * {float(big)!r}] is too large to be a number"]


def test_assignment_of_a_non_finite_literal():
    _, diagnostics = run(f"#<a> = {'9' * 400}")
    assert diagnostics == ["t.txt:1:8: E009 #<a> = inf is not a usable number"]


# --- repeat blocks ----------------------------------------------------------------------------


def test_repeat_runs_its_body_n_times_and_assignments_advance():
    source = "#<x> = 0\nO<loop> repeat [3]\n  #<x> = [#<x> + 10]\n  G1 X#<x>\nO<loop> endrepeat\nG1 X0"
    statements, diagnostics = run(source)
    assert diagnostics == []
    assert [s.command.x_mm for s in statements] == [10, 20, 30, 0]
    assert [s.line for s in statements] == [4, 4, 4, 6]
    assert [s.loop for s in statements] == [(0,), (1,), (2,), ()]


def test_nested_repeats():
    source = ("#<i> = 0\nO<outer> repeat [2]\n O<inner> repeat [3]\n  #<i> = [#<i> + 1]\n  G1 X#<i>\n"
              " O<inner> endrepeat\n G4 P1\nO<outer> endrepeat")
    statements, diagnostics = run(source)
    assert diagnostics == []
    assert [(s.code, s.loop) for s in statements] == [
        ("G1", (0, 0)), ("G1", (0, 1)), ("G1", (0, 2)), ("G4", (0,)),
        ("G1", (1, 0)), ("G1", (1, 1)), ("G1", (1, 2)), ("G4", (1,)),
    ]
    assert [s.command.x_mm for s in statements if s.code == "G1"] == [1, 2, 3, 4, 5, 6]


@pytest.mark.parametrize("count, runs", [("0", 0), ("[0]", 0), ("1", 1), ("[2 + 2]", 4), ("#<n>", 5), ("[#<n> - 5]", 0)])
def test_repeat_counts(count, runs):
    statements, diagnostics = run(f"#<n> = 5\nO100 repeat {count}\nG4 P1\nO100 endrepeat")
    assert diagnostics == [] and len(statements) == runs


def test_count_is_evaluated_when_the_block_starts():
    source = "#<n> = 2\nO<a> repeat [#<n>]\n#<n> = 10\nG4 P1\nO<a> endrepeat"
    assert len(run(source)[0]) == 2


def test_a_body_that_runs_zero_times_is_still_parsed():
    statements, diagnostics = run("O<a> repeat [0]\nG1 X(\nG1 X[1/0]\nO<a> endrepeat")
    assert statements == [] and diagnostics == ["t.txt:2:5: E001 expected a number after X"]


def test_an_error_inside_a_loop_is_reported_once():
    _, diagnostics = run("O<a> repeat [100]\nG4 P-1\nO<a> endrepeat")
    assert diagnostics == ["t.txt:2:4: E005 P must not be negative, not -1"]


def test_a_loop_error_that_appears_only_in_a_later_iteration():
    source = "#<p> = 2\nO<a> repeat [4]\n#<p> = [#<p> - 1]\nG4 P#<p>\nO<a> endrepeat"
    statements, diagnostics = run(source)
    assert [s.command.delay_ms for s in statements] == [1, 0]
    assert diagnostics == ["t.txt:4:4: E005 P must not be negative, not -1"]


@pytest.mark.parametrize("source, expected", [
    ("O<a> repeat [1]\nG4 P1\nO<b> endrepeat", [
        "t.txt:1:1: E008 O<a> repeat is never closed", "t.txt:3:1: E008 O<b> endrepeat has no O<b> repeat before it"]),
    ("O<a> endrepeat", ["t.txt:1:1: E008 O<a> endrepeat has no O<a> repeat before it"]),
    ("O<a> repeat [1]\nO<b> repeat [1]\nG4 P1\nO<a> endrepeat",
     ["t.txt:2:1: E008 O<b> repeat is not closed before O<a> endrepeat (line 4)"]),
    ("O<a> repeat [1]\nO<a> repeat [1]\nO<a> endrepeat\nO<a> endrepeat", ["t.txt:2:1: E008 O<a> is already open (line 1)"]),
    ("O<a> repeat\nO<a> endrepeat", ["t.txt:1:1: E008 O<a> repeat needs a count"]),
    ("O<a> repeat [1]\nO<a> endrepeat [2]", ["t.txt:2:16: E008 O<a> endrepeat takes no count"]),
    ("O<a> repeat [2.5]\nO<a> endrepeat", ["t.txt:1:13: E008 a repeat count must be a whole number >= 0, not 2.5"]),
    ("O<a> repeat [-1]\nO<a> endrepeat", ["t.txt:1:13: E008 a repeat count must be a whole number >= 0, not -1"]),
    ("O<a> repeat [#<n>]\nO<a> endrepeat", ["t.txt:1:14: E007 parameter #<n> is not defined"]),
    ("O<a> while [1]\nG4 P1", ["t.txt:1:1: E008 O<a> while is not supported: only repeat and endrepeat"]),
])
def test_repeat_structure_errors(source, expected):
    assert run(source)[1] == expected


def test_labels_are_case_insensitive_and_may_be_numbers():
    assert len(run("O<Loop> repeat [2]\nG4 P1\no<LOOP> ENDREPEAT\nO100 repeat [1]\nG4 P1\nO100 endrepeat")[0]) == 3


def test_from_line_inside_a_repeat_block_is_refused():
    statements, diagnostics = run("G4 P1\nO<a> repeat [2]\nG4 P2\nO<a> endrepeat\nG4 P3", from_line=3)
    assert diagnostics == ["t.txt:3:1: E010 cannot resume at line 3: it is inside O<a> repeat (lines 2–4)"]


def test_from_line_inside_an_arc_is_refused():
    _, diagnostics = run("G300 X1 R5\n\nG301 X2", from_line=2)
    assert diagnostics == ["t.txt:2:1: E010 cannot resume at line 2: it is inside the arc G300 (line 1) … G301 (line 3)"]


def test_from_line_past_the_end_is_refused():
    assert run("G4 P1\nG4 P2", from_line=9)[1] == ["t.txt:9:1: E010 cannot resume at line 9: the file has 2 lines"]


def test_a_repeat_line_breaks_an_arc():
    _, diagnostics = run("G300 X1 R5\nO<a> repeat [1]\nG301 X2\nO<a> endrepeat")
    assert diagnostics[0] == "t.txt:1:1: E006 G300 must be followed directly by G301"


def test_arcs_inside_a_loop():
    statements, diagnostics = run("O<a> repeat [2]\nG300 X1 R5\nG301 X2\nO<a> endrepeat")
    assert diagnostics == [] and [s.code for s in statements] == ["G300", "G301"] * 2


def test_only_the_body_is_buffered():
    # A body is held as parsed lines until its endrepeat; lines after it stream as before.
    def lines():
        yield "O<a> repeat [2]"
        yield "G4 P1"
        yield "O<a> endrepeat"
        for _ in range(3):
            yield "G4 P2"
    seen = []
    for statement in compile_lines(lines(), "t.txt"):
        seen.append(statement.command.delay_ms)
    assert seen == [1, 1, 2, 2, 2]
