"""Each statement of the motion-script language → the exact command object it produces.

A table of (script, commands) read like DESIGN.md's language table; every script starts from
a known state (KNOWN) so each row shows one statement's own words.
"""

from __future__ import annotations

import pytest

from armctl.core.protocol import (
    AccelLinearMove, ArcEnd, ArcStart, Delay, GoToPose, JointMove, LinearMove, MCode, PauseToggle, ResetArm,
    ResetConnector, RunProgram, SetWorktableOrigin, StructureMode,
)
from armctl.script import InitialState, Statement, compile_text

KNOWN = InitialState(
    pose=(100, 0, 50, 0, 0, 0), joints_deg=(0, 0, 0, 0, 0, 0), pwm_us={1: 1500}, speed_mm_min=3000,
    speed_deg_s=20, accel_mm_s2=500,
)


def commands(source: str, initial: InitialState | None = KNOWN, **options) -> list:
    job = compile_text(source, "t.txt", initial, **options)
    result = [statement.command for statement in job]
    assert job.diagnostics == [], [d.render() for d in job.diagnostics]
    return result


def linear(x=100.0, y=0.0, z=50.0, b0=0.0, b1=0.0, w=0.0, pwm=1500.0, speed=3000.0, e0=0.0, e1=0.0, channel=1):
    return LinearMove(x, y, z, b0, b1, w, pwm, speed, e0, e1, channel)


STATEMENTS = [
    # G1: X Y Z mm, A B C attitude deg, U V external deg, S PWM, T channel, F mm/min
    ("G1 X10 Y20 Z30 A1 B2 C3 U4 V5 S600 F1200", [linear(10, 20, 30, 1, 2, 3, 600, 1200, 4, 5)]),
    ("G1 X-1.5 Y.5 Z+2 A-.25 B5. C0", [linear(-1.5, 0.5, 2, -0.25, 5, 0)]),
    ("G1 T2 S2000", [linear(pwm=2000, channel=2)]),
    ("G1 T4 S500 X1", [linear(x=1, pwm=500, channel=4)]),
    # G220 / G222 / G230: modes 0 / 1 / 2, K acceleration, F speed1, Q speed0 (G230 only)
    ("G220 X1 K-200 F900", [AccelLinearMove(0, 1, 0, 50, 0, 0, 0, -200, 900)]),
    ("G222 Y2 U1 V2", [AccelLinearMove(1, 100, 2, 50, 0, 0, 0, 500, 3000, 0, 1, 2)]),
    ("G230 Z3 K100 F2000 Q400", [AccelLinearMove(2, 100, 0, 3, 0, 0, 0, 100, 2000, 400)]),
    # G6: J1=…J6= deg, S, U V, H smoothing, F deg/s
    ("G6 J1=10 J2=20 J3=30 J4=40 J5=50 J6=60 S700 U1 V2 H3 F15",
     [JointMove(10, 20, 30, 40, 50, 60, 700, 15, 1, 2, 3)]),
    ("G6 J3=-45.5", [JointMove(0, 0, -45.5, 0, 0, 0, 1500, 20)]),
    # G300 then G301: an arc, two frames
    ("G300 X10 Y10 Z50 R25 F600 S900\nG301 X20 Y0 F300",
     [ArcStart(10, 10, 50, 0, 0, 0, 900, 25, 600), ArcEnd(20, 0, 50, 0, 0, 0, 900, 300)]),
    ("G300 A5 B6 C7 R1\nG301 Z0", [ArcStart(100, 0, 50, 5, 6, 7, 1500, 1, 3000), ArcEnd(100, 0, 0, 5, 6, 7, 1500, 3000)]),
    ("G4 P250", [Delay(250)]),
    ("G4 P0", [Delay(0)]),
    ("M3", [MCode(3)]),
    ("M0\nM117", [MCode(0), MCode(117)]),
    ("G54 X1 Y2 Z3", [SetWorktableOrigin(1, 2, 3)]),
    ("RESET", [ResetArm()]),
    ("RESET CONNECTOR", [ResetConnector()]),
    ("PAUSE", [PauseToggle()]),
    ("POSE 0\nPOSE 3", [GoToPose(0), GoToPose(3)]),
    ("PROGRAM 0\nPROGRAM 15", [RunProgram(0), RunProgram(15)]),
    ("MODE 0\nMODE 1", [StructureMode(0), StructureMode(1)]),
    ("G90\nG91", []),
]


@pytest.mark.parametrize("source, expected", STATEMENTS, ids=[s.split("\n")[0] for s, _ in STATEMENTS])
def test_statement_produces_exact_command(source, expected):
    assert commands(source) == expected


@pytest.mark.parametrize("source, expected", [
    ("g1 x10 y20", [linear(10, 20)]),
    ("G1 x10 Y20 z30", [linear(10, 20, 30)]),
    ("g6 j1=5", [JointMove(5, 0, 0, 0, 0, 0, 1500, 20)]),
    ("reset connector\nReset\npause\nPose 1\nprogram 2\nmode 1",
     [ResetConnector(), ResetArm(), PauseToggle(), GoToPose(1), RunProgram(2), StructureMode(1)]),
    ("g300 x1 r2\ng301 x3", [ArcStart(1, 0, 50, 0, 0, 0, 1500, 2, 3000), ArcEnd(3, 0, 50, 0, 0, 0, 1500, 3000)]),
    ("m5", [MCode(5)]),
])
def test_letters_and_keywords_are_case_insensitive(source, expected):
    assert commands(source) == expected


@pytest.mark.parametrize("source", [
    "N10 G1 X10",
    "n10 G1 X10",
    "N10G1X10",
    "G01 X10",
    "G1X10",
    "G1 X10 ; a comment",
    "G1 X10;comment",
    "G1 (inline) X10 (another)",
    "  G1\tX10  ",
    "G1 X10 (a ; inside) ; and ( here",
    "G1 X10\r",
])
def test_line_numbers_comments_and_spacing(source):
    assert commands(source) == [linear(10)]


@pytest.mark.parametrize("source", ["", "; only a comment", "(only inline)", "N5", "N5 ; c", "   ", "(a) (b) ; c"])
def test_lines_with_nothing_to_do(source):
    assert commands(source) == []


def test_keyword_arguments_take_values():
    assert commands("#<p> = 2\nPOSE #<p>\nPROGRAM [#<p> * 3]\nMODE [1 - 1]") == [GoToPose(2), RunProgram(6), StructureMode(0)]


def test_statement_carries_its_source():
    [statement] = compile_text("; header\n  N7 g1 X10 Y2 ; move\n", "job.txt", KNOWN)
    assert isinstance(statement, Statement)
    assert statement.line == 2
    assert statement.code == "G1"
    assert dict(statement.words) == {"X": 10.0, "Y": 2.0}
    assert statement.relative is False
    assert statement.loop == ()
    span = statement.span
    assert (span.file, span.line, span.column, span.end_column) == ("job.txt", 2, 6, 8)
    assert span.text == "  N7 g1 X10 Y2 ; move"
    assert span.snippet == "g1"
    word = statement.word_span("Y")
    assert (word.column, word.end_column, word.snippet) == (13, 15, "Y2")
    assert statement.word_span("Z") is None


def test_keyword_statement_span_covers_the_keywords():
    [statement] = compile_text("reset  connector", "t.txt", KNOWN)
    assert statement.code == "RESET CONNECTOR"
    assert statement.span.snippet == "reset  connector"


def test_commands_encode_to_frames():
    frames = [s.command.encode() for s in compile_text("G1 X1\nG4 P5\nRESET", "t.txt", KNOWN)]
    assert [len(f) for f in frames] == [48, 48, 48]
    assert frames[0][:3] == bytes([0xEE, ord("1"), 1])
