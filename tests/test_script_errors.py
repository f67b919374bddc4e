"""Every diagnostic the language emits: exact sentence, code and column; rendering; recovery.

One run reports every error of a file (each at its own line and column), keeps going after
a bad line, and never repeats an error another one caused.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from armctl.errors import ScriptError
from armctl.script import RULES, Diagnostic, InitialState, SourceSpan, check_lines, compile_file, compile_text
from armctl.script.syntax_errors import START_HINT

DATA = Path(__file__).parent / "data" / "scripts"
KNOWN = InitialState(
    pose=(100, 0, 50, 0, 0, 0), joints_deg=(0, 0, 0, 0, 0, 0), pwm_us={1: 1500}, speed_mm_min=3000,
    speed_deg_s=20, accel_mm_s2=500,
)


def diagnose(source: str, initial=KNOWN, **options) -> list[Diagnostic]:
    return check_lines(source.splitlines(), "t.txt", initial, **options)


def only(source: str, initial=KNOWN, **options) -> tuple:
    [diagnostic] = diagnose(source, initial, **options)
    span = diagnostic.span
    return diagnostic.code, diagnostic.message, span.line, span.column, span.end_column


# (line, code, message, column, end_column); the line runs after a known state.
SYNTAX = [
    ("G1 X", "E001", "expected a number after X", 5, 5),
    ("G1 X Y5", "E001", "expected a number after X", 5, 6),
    ("G1 X 5", "E001", "expected a number after X", 5, 6),
    ("G6 J1=", "E001", "expected a number after J1=", 7, 7),
    ("G6 J1=x", "E001", "expected a number after J1=", 7, 8),
    ("G1 X1.2.3", "E001", "expected a word such as X10, found '.3'", 8, 10),
    ("G1 X5 $", "E001", "expected a word such as X10, found '$'", 7, 8),
    ("G1 X5 \x01", "E001", "expected a word such as X10, found '\\x01'", 7, 8),
    ("G1 X5 é", "E001", "expected a word such as X10, found 'é'", 7, 8),
    ("G1 X5 (unclosed", "E001", "comment '(' is not closed on this line", 7, 8),
    ("G1 X5 RESET", "E001", "one statement per line: RESET must be on a line of its own", 7, 12),
    ("X5 Y5", "E001", "a statement cannot start with 'X5'", 1, 3),
    ("G X5", "E001", "expected a number after G", 2, 3),
    ("N", "E001", "expected a number after N", 2, 2),
    ("O", "E001", "expected a label after O: O<name> or O123", 2, 2),
    ("#5 = 3", "E001", "numbered parameters are not supported: name it, as in #<name>", 1, 2),
    ("#<a> 5", "E001", "expected '=' after #<a>, found '5'", 6, 7),
    ("#<a> =", "E001", "expected a number, #<name> or [expression] after '='", 7, 7),
    ("#<a> = 1 + 2", "E001", "unexpected '+': an expression goes in brackets", 10, 11),
    ("#<a> = [1 + (2)]", "E001", "expected a number, #<name> or [expression] after '+', found ']'", 16, 17),
    ("G1 X[1+", "E001", "expected a number, #<name> or [expression] after '+'", 8, 8),
    ("G1 X[1 2]", "E001", "expected an operator (+ - * /) or ']', found '2'", 8, 9),
    ("G1 X[1", "E001", "missing ']' to close the '[' opened at column 5", 7, 7),
    ("O<a>", "E001", "expected repeat or endrepeat after O<a>", 5, 5),
    ("RESET CONNECTOR 5", "E001", "unexpected '5' after the end of the statement", 17, 18),
    ("POSE x", "E001", "expected a number, #<name> or [expression] after 'POSE', found 'x'", 6, 7),
]


@pytest.mark.parametrize("line, code, message, column, end", SYNTAX, ids=[row[0] for row in SYNTAX])
def test_syntax_errors_are_plain_sentences_at_the_offending_character(line, code, message, column, end):
    assert only(line) == (code, message, 1, column, end)


def test_statement_start_error_has_a_hint():
    [diagnostic] = diagnose("X5 Y5")
    assert diagnostic.hint == START_HINT


SEMANTIC = [
    ("G4 Z5 P1", "E002", "unknown word 'Z' in G4", 4, 6),
    ("G1 X5 Q3", "E002", "unknown word 'Q' in G1", 7, 9),
    ("G1 X5 N10", "E002", "line number N10 must start the line", 7, 10),
    ("G1 X5 G1", "E002", "one statement per line: G1 must be on a line of its own", 7, 9),
    ("G90 X5", "E002", "unknown word 'X' in G90", 5, 7),
    ("M3 S5", "E002", "unknown word 'S' in M3", 4, 6),
    ("G2 X5", "E002", "unknown statement G2", 1, 3),
    ("g0", "E002", "unknown statement G0", 1, 3),
    ("PAUSED", "E002", "unknown statement 'PAUSED' (did you mean PAUSE?)", 1, 7),
    ("RESET FOO", "E002", "unknown statement 'RESET FOO'", 1, 10),
    ("RESET 5", "E002", "RESET takes no number", 7, 8),
    ("G1 X5 X6", "E003", "X appears twice in G1", 7, 9),
    ("G6 j1=5 J1=6", "E003", "J1 appears twice in G6", 9, 13),
    ("G4", "E004", "G4 needs P", 1, 3),
    ("G54 X1 Y2", "E004", "G54 needs Z", 1, 4),
    ("G230 X1", "E004", "G230 needs Q", 1, 5),
    ("POSE", "E004", "POSE needs a number", 1, 5),
    ("G1 S3000", "E005", "S = 3000 is outside 500…2500", 4, 9),
    ("G1 F0", "E005", "F must be greater than 0, not 0", 4, 6),
    ("G1 F-5", "E005", "F must be greater than 0, not -5", 4, 7),
    ("G1 T5", "E005", "T5 is not a PWM channel (1…4)", 4, 6),
    ("G220 K5000", "E005", "K = 5000 is outside -3200…3200", 6, 11),
    ("G6 H7", "E005", "H = 7 is outside 0…6", 4, 6),
    ("G6 H1.5", "E005", "H must be a whole number, not 1.5", 4, 8),
    ("G300 X1 R0\nG301 X2", "E005", "R must be greater than 0, not 0", 9, 11),
    ("G4 P-1", "E005", "P must not be negative, not -1", 4, 7),
    ("G1 X" + "9" * 40, "E005", "X is too large for a frame: a 32-bit float holds at most ±3.4e38", 4, 45),
    ("G1 X1e400", "E002", "unknown word 'E' in G1", 6, 10),
    ("M99999999999", "E005", "M99999999999 is outside the M-code range (a 32-bit signed integer)", 1, 13),
    ("POSE 4", "E005", "POSE = 4 is outside 0…3", 6, 7),
    ("PROGRAM 1.5", "E005", "PROGRAM must be a whole number, not 1.5", 9, 12),
    ("MODE 2", "E005", "MODE = 2 is outside 0…1", 6, 7),
    ("G301 X1", "E006", "G301 has no G300 before it", 1, 5),
    ("G1 X#<nope>", "E007", "parameter #<nope> is not defined", 5, 12),
    ("G1 X[1 / [2 - 2]]", "E009", "division by zero in [1 / [2 - 2]]", 6, 17),
    ("#<a> = [1 / 0]", "E009", "division by zero in [1 / 0]", 9, 14),
]


@pytest.mark.parametrize("source, code, message, column, end", SEMANTIC, ids=[row[0][:30] for row in SEMANTIC])
def test_semantic_errors_point_at_the_word_to_blame(source, code, message, column, end):
    got = only(source)
    assert got[:2] == (code, message) and got[3:] == (column, end)


def test_missing_values_point_at_the_statement_with_a_hint():
    [diagnostic] = diagnose("G1 X5", None)
    assert str(diagnostic) == "t.txt:1:1: E004 G1 needs Y, Z, A, B, C, S, F: no earlier move set them"
    assert diagnostic.hint == "write Y Z A B C S F on this line, or start from a known state"


def test_modal_value_out_of_range_points_at_the_statement():
    [diagnostic] = diagnose("G300 X1 R5\nG301 X2 F0\nG1 X3")
    assert (str(diagnostic), diagnostic.hint) == (
        "t.txt:3:1: E005 F must be greater than 0, not 0",
        "F is modal: the value from an earlier line applies; write F here",
    )


def test_every_out_of_range_word_of_a_line_is_reported():
    assert [d.message for d in diagnose("G1 S3000 F0 X1")] == [
        "S = 3000 is outside 500…2500", "F must be greater than 0, not 0"]


def test_range_errors_are_reported_even_when_values_are_missing():
    messages = [d.message for d in diagnose("G1 X5 S9999", None)]
    assert messages == ["G1 needs Y, Z, A, B, C, F: no earlier move set them", "S = 9999 is outside 500…2500"]


def test_a_value_that_failed_is_not_reported_again_on_later_lines():
    # S is poisoned by line 1; line 2 needs it but is not reported; line 3 sets S again.
    diagnostics = diagnose("G1 S3000\nG1 X5\nG1 S1000 X6\nG1 F0")
    assert [(d.span.line, d.code) for d in diagnostics] == [(1, "E005"), (4, "E005")]


def test_missing_values_are_reported_once():
    diagnostics = diagnose("G1 X1\nG1 X2\nG1 X3", None)
    assert [d.span.line for d in diagnostics] == [1]


def test_arc_pairing_errors():
    assert [str(d) for d in diagnose("G300 X1 R5\nG1 X2\nG300 X1 R5\n; comment\n\nG301 X2\nG300 X1 R5")] == [
        "t.txt:1:1: E006 G300 must be followed directly by G301",
        "t.txt:7:1: E006 G300 must be followed directly by G301",
    ]
    hints = [d.hint for d in diagnose("G300 X1 R5\nM3\nG300 X1 R5")]
    assert hints == ["line 2 has an M code", "the file ends after it"]


def test_a_broken_arc_yields_neither_half():
    job = compile_text("G300 X1 R5\nG1 X2\nG300 X1 R5 S9999\nG301 X2\nG1 X3 S1000", "t.txt", KNOWN)
    assert [s.code for s in job] == ["G1", "G1"]
    assert [d.code for d in job.diagnostics] == ["E006", "E005"]


def test_three_mistakes_give_three_located_diagnostics():
    job = compile_file(DATA / "three_mistakes.txt")
    statements = list(job)
    rendered = "\n".join(d.render() for d in job.diagnostics).replace(str(DATA) + "/", "")
    assert rendered + "\n" == (DATA / "three_mistakes.expected").read_text(encoding="utf-8")
    assert job.error_count == 3 and not job.ok
    assert [s.line for s in statements] == [2, 3, 5, 9]  # good lines still compile


def test_render_is_ruff_style():
    span = SourceSpan("job.txt", 12, 4, 9, "G1 S3000 X1")
    text = Diagnostic.of("E005", span, "S = 3000 is outside 500…2500", "the servo takes 500…2500 µs").render()
    assert text == (
        "job.txt:12:4: E005 S = 3000 is outside 500…2500\n"
        "   |\n"
        "12 | G1 S3000 X1\n"
        "   |    ^^^^^\n"
        "   |\n"
        "   = hint: the servo takes 500…2500 µs"
    )


def test_render_keeps_tabs_and_replaces_control_characters():
    span = SourceSpan("t", 1, 3, 4, "\tG\x01X")
    assert Diagnostic.of("E001", span, "m").render().splitlines()[2:] == ["1 | \tG\ufffdX", "  | \t ^"]


def test_render_elides_long_lines_around_the_span():
    text = "G1 " + "X1 " * 100 + "Q5"
    span = SourceSpan("t", 1, len(text) - 1, len(text) + 1, text)
    source, caret = Diagnostic.of("E002", span, "m").render().splitlines()[2:4]
    assert source.startswith("1 | …") and len(source) < 120
    assert caret.index("^") == source.index("Q5")


def test_render_survives_undecodable_bytes():
    span = SourceSpan("t", 1, 4, 5, "G1 \udcff")
    Diagnostic.of("E011", span, "m").render().encode("utf-8")


def test_rule_table_covers_every_code_and_is_stable():
    assert sorted(RULES) == [f"E{n:03}" for n in range(1, 13)]
    assert all(rule.severity == "error" and rule.summary for rule in RULES.values())


def test_diagnostic_as_dict():
    [diagnostic] = diagnose("G4 P-1")
    assert diagnostic.as_dict() == {
        "file": "t.txt", "line": 1, "column": 4, "end_column": 7, "code": "E005", "severity": "error",
        "message": "P must not be negative, not -1", "hint": None,
    }


def test_raise_for_errors_and_script_error():
    job = compile_text("G4", "t.txt")
    list(job)
    with pytest.raises(ScriptError) as caught:
        job.raise_for_errors()
    assert caught.value.diagnostics == job.diagnostics
    compile_text("G4 P1", "t.txt").raise_for_errors()


def test_max_diagnostics_keeps_the_first_and_counts_all():
    job = compile_text("\n".join(["G4"] * 50), "t.txt", max_diagnostics=10)
    assert job.finish() == job.diagnostics and len(job.diagnostics) == 10
    assert job.error_count == 50


def test_a_compilation_is_iterated_once():
    job = compile_text("G4 P1", "t.txt")
    list(job)
    with pytest.raises(RuntimeError):
        iter(job)


# --- not text -----------------------------------------------------------------------------


def test_undecodable_bytes_are_located(tmp_path):
    path = tmp_path / "latin1.txt"
    path.write_bytes(b"G4 P1\nG4 P2 ; caf\xe9\nG4 P3\n")
    job = compile_file(path)
    assert [s.line for s in job] == [1, 3]
    [diagnostic] = job.diagnostics
    assert (diagnostic.code, diagnostic.message, diagnostic.span.column) == ("E011", "byte 0xe9 is not UTF-8 text", 12)


def test_a_binary_file_stops_at_its_first_nul_byte(tmp_path):
    path = tmp_path / "image.bin"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)) * 4)
    job = compile_file(path)
    assert list(job) == []
    codes = [d.code for d in job.diagnostics]
    assert codes[-1] == "E011" and "binary" in job.diagnostics[-1].message and len(codes) <= 3


def test_an_overlong_line_is_reported_without_reading_it_whole(tmp_path):
    path = tmp_path / "long.txt"
    path.write_bytes(b"G4 P1\nG1 " + b"X1 " * 1_000_000 + b"\nG4 P2\n")
    job = compile_file(path)
    assert [s.line for s in job] == [1, 3]
    [diagnostic] = job.diagnostics
    assert diagnostic.code == "E011" and diagnostic.span.line == 2
    assert diagnostic.message.endswith("a statement has at most 4096")


def test_utf8_bom_and_crlf_are_fine(tmp_path):
    path = tmp_path / "windows.txt"
    path.write_bytes("\ufeffG4 P1 ; café\r\nG4 P2\r\n".encode("utf-8"))
    job = compile_file(path)
    assert [s.command.delay_ms for s in job] == [1, 2] and job.ok


def test_two_different_errors_on_the_same_statement_are_both_reported():
    assert [d.message for d in diagnose("G300 X1\nG301 X2", None)] == [
        "G300 needs Y, Z, A, B, C, S, F: no earlier move set them", "G300 needs R"]
