"""Arbitrary input never raises: it compiles, or gives located diagnostics.

The one invariant of a parser fed noise (after h11's fuzz target): the only outcome besides
statements is a ``Diagnostic`` whose span lies on its line — for any text, including
non-ASCII, control characters, undecodable bytes, huge numbers and very long lines.
"""

from __future__ import annotations

import io

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armctl.script import InitialState, compile_lines, iter_lines

KNOWN = InitialState(pose=(0, 0, 0, 0, 0, 0), joints_deg=(0,) * 6, pwm_us={1: 1500}, speed_mm_min=100,
                     speed_deg_s=10, accel_mm_s2=100)

fragments = st.sampled_from([
    "G1", "G6", "G300", "G301", "G4", "G54", "G91", "G90", "M3", "X", "Y-", "Z.5", "J1=", "J2=3", "S1500", "S9999",
    "T2", "F0", "F100", "R5", "P", "H9", "Q1", "K-1", "U", "V1", "X1e400", "X" + "9" * 400, "RESET", "CONNECTOR",
    "PAUSE", "POSE", "PROGRAM", "MODE", "#<a>", "#<b>", "=", "[", "]", "+", "-", "*", "/", "0", "1.5", "(", ")", ";",
    " ", "\t", "O<a>", "repeat", "endrepeat", "N5", "é", "\x00", "\x7f", "\u2028", "\udcfe", "😀", "\r", "\\", "$",
])
noisy_line = st.one_of(st.lists(fragments, max_size=20).map("".join), st.text(max_size=80))
scripts = st.lists(noisy_line, max_size=12)


def check(job, script):
    statements = list(job)
    assert job.finished
    for diagnostic in job.diagnostics:
        span = diagnostic.span
        assert span.line >= 1 and diagnostic.code.startswith("E")
        if span.line <= len(script):
            text = script[span.line - 1].rstrip("\r\n")
            assert span.text == text
            assert 1 <= span.column <= span.end_column <= len(text) + 1 or diagnostic.code == "E010"
        diagnostic.render().encode("utf-8")
    assert job.error_count >= len(job.diagnostics)
    return statements


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scripts, st.sampled_from([None, KNOWN]), st.integers(1, 14))
def test_noise_never_raises(script, initial, from_line):
    check(compile_lines(script, "fuzz.txt", initial, from_line=from_line), script)


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=400))
def test_bytes_never_raise(data):
    script = list(iter_lines(io.BytesIO(data)))
    check(compile_lines(script, "fuzz.bin", KNOWN), script)


@settings(max_examples=20, deadline=None)
@given(st.integers(1, 3), st.sampled_from(["X1 ", "(c)", "[", "#<a>", "X[1+", "é", "9"]))
def test_very_long_lines(scale, piece):
    line = "G1 " + piece * (1500 * scale)
    check(compile_lines([line, "G4 P1"], "long.txt", KNOWN), [line, "G4 P1"])


def test_deeply_nested_brackets():
    line = "G1 X" + "[" * 300 + "1" + "]" * 300
    assert [s.command.x_mm for s in check(compile_lines([line], "t.txt", KNOWN), [line])] == [1]


def test_expressions_nested_too_deeply_are_refused_not_crashed():
    for value in ("[" + "1+" * 150 + "1]", "[" + "-" * 150 + "#<a>]", "[1" + "+1" * 1500 + "]"):
        job = compile_lines(["#<a> = 1", "G1 X" + value], "t.txt", KNOWN)
        assert list(job) == []
        assert [d.message for d in job.diagnostics] == ["expression nested more than 100 operations deep"]
