"""armctl lint's rules: one located diagnostic per rule, and each rule's edges.

The spec is tests/data/lint/every_rule.txt: every line marked ``; expect: CODE`` gets exactly
one diagnostic with that code and no other line gets any.  The other tests pin what each rule
must and must not say, through ``lint_lines`` (no CLI).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from armctl.lint import RULES, Selection, lint_lines
from armctl.host.profile import default_profile, load_profile
from armctl.script import iter_lines

DATA = Path(__file__).parent / "data" / "lint"
_EXPECT = re.compile(r"; expect: ([A-Z]\d{3})")


def _default():
    return default_profile()


@pytest.fixture(scope="module")
def test_profile():
    return load_profile(DATA / "profile.toml")


def lint(text: str, profile=None, **options):
    return lint_lines(text.splitlines(), "job.txt", profile or _default(), **options)


def codes(text: str, profile=None, **options) -> list[tuple[int, str]]:
    return [(d.span.line, d.code) for d in lint(text, profile, **options).diagnostics]


START = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n"  # a clean first move for the default profile


# --- the one-per-rule file ------------------------------------------------------------------------


def test_every_rule_file_gets_one_located_diagnostic_per_marked_line(test_profile):
    path = DATA / "every_rule.txt"
    with open(path, "rb") as stream:
        lines = list(iter_lines(stream))
    expected = {(number, m.group(1)) for number, line in enumerate(lines, 1) if (m := _EXPECT.search(line))}
    with open(path, "rb") as stream:
        report = lint_lines(iter_lines(stream), str(path), test_profile)
    found = [(d.span.line, d.code) for d in report.diagnostics]
    assert sorted(found) == sorted(expected)
    for diagnostic in report.diagnostics:  # located: the span is on its own source line
        assert diagnostic.span.text == lines[diagnostic.span.line - 1].rstrip("\r\n")
        assert 1 <= diagnostic.span.column <= max(len(diagnostic.span.text), 1)
        # the code's severity, except an error on the built-in profile's illustrative numbers
        illustrative = "illustrative numbers from the built-in profile" in diagnostic.message
        assert diagnostic.severity == ("warning" if illustrative else RULES[diagnostic.code].severity)


def test_every_rule_file_covers_every_code_but_two(test_profile):
    text = (DATA / "every_rule.txt").read_bytes().decode("utf-8", "surrogateescape")
    covered = set(_EXPECT.findall(text))
    # E010 is about compile/run --from-line; L403 (empty script) cannot share a file with others.
    assert covered == set(RULES) - {"E010", "L403"}


# --- E004: missing values (speed, the first move, G91) are the language's ------------------------


@pytest.mark.parametrize("script, column, words", [
    ("G1 X250 Y0 Z150 S1000 F3000", 1, "A, B, C"),  # the first move leaves the attitude unknown
    ("G1 X250 Y0 Z150 A180 B0 C0 F3000", 1, "S"),  # … or the gripper's PWM
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000", 1, "F"),  # no speed set before in this family
    ("G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000", 1, "F"),
])
def test_missing_values_are_e004_at_the_statement(script, column, words):
    report = lint(script)
    assert [(d.code, d.span.column) for d in report.diagnostics] == [("E004", column)]
    assert words in report.diagnostics[0].message


def test_relative_move_from_an_unknown_position_is_e004_at_the_word():
    report = lint("G91\nG1 Z10 A180 B0 C0 S1000 F3000")
    assert ("E004", 2) in [(d.code, d.span.line) for d in report.diagnostics]
    assert any("relative (G91)" in d.message and d.span.snippet == "Z10" for d in report.diagnostics)


def test_relative_move_after_a_fixed_pose_is_e004():
    # POSE 2 leaves the Cartesian target unknown to the host: G91 would depend on the arm.
    report = lint(START + "POSE 2\nG91\nG1 Z10")
    assert [(d.code, d.span.line) for d in report.diagnostics][-1] == ("E004", 4)


def test_relative_moves_from_a_known_pose_are_fine():
    assert codes(START + "G91\nG1 Z-50\nG1 X20\nG90\nG1 Z150") == []


# --- L1xx geometry ------------------------------------------------------------------------------


def test_a_clean_arc_reports_nothing():
    assert codes(START + "G1 X280 Y0 Z20\nG300 X250 Y30 Z20 R30\nG301 X220 Y0 Z20") == []


def test_arc_ending_at_its_start_is_degenerate():
    report = lint(START + "G300 X260 Y10 Z150 R10\nG301 X250 Y0 Z150")
    assert [(d.code, d.span.line) for d in report.diagnostics] == [("L101", 3)]
    assert "ends where it starts" in report.diagnostics[0].message


def test_arc_radius_hint_gives_the_fix():
    report = lint(START + "G300 X260 Y10 Z150 R12\nG301 X270 Y0 Z150")
    (diagnostic,) = report.diagnostics
    assert (diagnostic.code, diagnostic.span.snippet, diagnostic.hint) == ("L102", "R12", "write R10.00")


def test_radius_within_tolerance_is_accepted():
    assert codes(START + "G300 X260 Y10 Z150 R10.3\nG301 X270 Y0 Z150") == []


def test_arc_bulging_out_of_the_workspace():
    # circle centre (220, 0, 0), radius 30: the three points are inside the box (z >= -20) but
    # the arc from (250, 0, 0) down through (197.02, 0, -19.28) to (190, 0, 0) dips to z = -30
    script = START + "G1 X250 Y0 Z0\nG300 X197.02 Y0 Z-19.28 R30\nG301 X190 Y0 Z0"
    (diagnostic,) = lint(script).diagnostics
    assert (diagnostic.code, diagnostic.span.line) == ("L103", 4)
    assert "the arc from line 3 passes" in diagnostic.message


def test_workspace_is_checked_in_the_robot_frame_after_g54():
    inside_only_with_origin = "G54 X0 Y0 Z-100\nG1 X250 Y0 Z90 A180 B0 C0 S1000 F3000\nG1 Z40"
    report = lint(inside_only_with_origin)
    assert [(d.code, d.span.line) for d in report.diagnostics] == [("L103", 3)]
    assert "robot Z = -60.0" in report.diagnostics[0].message
    assert "worktable limits" in report.diagnostics[0].hint
    assert report.diagnostics[0].span.snippet == "Z40"


def test_unreachable_attitude_is_outside_workspace():
    # inside the box and the reach radius, but the tool pointing up there needs impossible joints
    report = lint("G1 X100 Y0 Z20 A0 B0 C0 S1000 F3000")
    assert [d.code for d in report.diagnostics] == ["L103"]


def test_joint_move_below_the_table_is_outside_workspace():
    report = lint("G6 J1=0 J2=80 J3=10 J4=0 J5=0 J6=0 S1000 F30")  # tool at robot Z = -58.7
    assert [d.code for d in report.diagnostics] == ["L103"]
    assert report.diagnostics[0].message.startswith("G6 puts the tool at robot")


def test_every_joint_outside_its_limits_is_reported_at_its_word():
    report = lint("G6 J1=200 J2=0 J3=0 J4=0 J5=-130 J6=0 S1000 F30")
    assert [(d.code, d.span.snippet) for d in report.diagnostics] == [("L104", "J1=200"), ("L104", "J5=-130")]


def test_loop_finding_is_reported_once_with_its_pass():
    # each pass climbs 200 mm: the second pass leaves the reach radius, the third the box too
    script = START + "G91\nO<up> repeat [4]\nG1 Z200\nO<up> endrepeat"
    report = lint(script)
    assert [(d.code, d.span.line) for d in report.diagnostics] == [("L103", 4)]
    assert "(repeat pass 2)" in report.diagnostics[0].message


# --- L2xx speeds ----------------------------------------------------------------------------------


def test_speed_checks_only_where_f_is_written():
    report = lint(START + "G1 X260 F9000\nG1 X270\nG1 X280")
    assert [(d.code, d.span.line, d.span.snippet) for d in report.diagnostics] == [("L201", 2, "F9000")]


def test_unit_slip_wins_over_speed_above_max():
    report = lint("G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F3000")
    assert [d.code for d in report.diagnostics] == ["L202"]
    report = lint("G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F200")
    assert [d.code for d in report.diagnostics] == ["L201"]


def test_slow_cartesian_speed_is_a_warning_with_the_conversion():
    (diagnostic,) = lint("G1 X250 Y0 Z150 A180 B0 C0 S1000 F30").diagnostics
    assert (diagnostic.code, diagnostic.severity) == ("L203", "warning")
    assert "F1800" in diagnostic.hint


def test_arc_end_speed_zero_is_not_a_unit_slip():
    assert codes(START + "G300 X260 Y10 Z150 R10 F600\nG301 X270 Y0 Z150 F0") == []


def test_acceleration_above_the_profile_maximum(test_profile):
    assert codes(START + "G222 X260 K1500 F3000", test_profile) == []
    assert codes(START + "G220 X260 K-2500 F3000", test_profile) == [(2, "L204")]


# --- L3xx PWM -------------------------------------------------------------------------------------


def test_unwired_channel_reported_where_t_selects_it():
    report = lint(START + "G1 T3 S1500\nG1 X260\nG1 T3 S1600\nG1 T1 S1000")
    assert [(d.code, d.span.line, d.span.snippet) for d in report.diagnostics] == [("L301", 2, "T3"), ("L301", 4, "T3")]


def test_pwm_inside_the_protocol_but_outside_the_profile(test_profile):
    assert codes(START + "G1 S2300") == []
    assert codes(START + "G1 S2300\nG1 S1000", test_profile) == [(2, "L302")]


# --- L4xx parameters, loops, empty scripts --------------------------------------------------------


def test_parameters_read_in_expressions_or_counts_are_used():
    script = "#<n> = 2\n#<z> = 150\n#<lift> = 10\n" + START.replace("Z150", "Z#<z>") + \
             "O<a> repeat [#<n>]\nG1 Z[#<z> - #<lift>]\nO<a> endrepeat"
    assert codes(script) == []


def test_unused_parameter_is_reported_at_its_first_assignment():
    report = lint("#<Spare> = 1\n" + START + "#<spare> = 2")
    assert [(d.code, d.span.line, d.span.snippet) for d in report.diagnostics] == [("L401", 1, "#<Spare>")]


def test_parameter_names_in_comments_do_not_count():
    report = lint("#<a> = 1 ; uses #<a>? no, a comment\n" + START + "(#<a>)")
    assert [d.code for d in report.diagnostics] == ["L401"]


def test_zero_repeat_count_from_a_parameter():
    report = lint(START + "#<n> = [2 - 2]\nO<a> repeat [#<n>]\nG1 Z140\nO<a> endrepeat")
    assert [(d.code, d.span.snippet) for d in report.diagnostics] == [("L402", "[#<n>]")]


def test_nested_counts_are_judged_only_when_literal():
    script = START + "#<n> = 0\nO<a> repeat [2]\n#<n> = [#<n> + 1]\nO<b> repeat [#<n>]\nG1 Z140\nO<b> endrepeat\n" \
                     "O<c> repeat [0]\nO<c> endrepeat\nO<a> endrepeat"
    assert codes(script) == [(8, "L402")]


@pytest.mark.parametrize("text, message", [("", "the file is empty"), ("; only a comment\n\n", "no statements"),
                                           ("#<a> = 1\nG4 P#<a> ; armctl: ignore", None)])
def test_empty_script(text, message):
    report = lint(text)
    if message is None:
        assert report.diagnostics == []
        return
    (diagnostic,) = report.diagnostics
    assert (diagnostic.code, diagnostic.severity, diagnostic.span.line) == ("L403", "warning", 1)
    assert message in diagnostic.message


# --- L5xx end state -------------------------------------------------------------------------------


def test_end_state_is_checked_only_when_the_profile_asks(test_profile):
    closed_and_paused = START + "G1 S2000\nPAUSE"
    assert codes(closed_and_paused) == []
    assert codes(closed_and_paused, test_profile) == [(2, "L501"), (3, "L502")]
    assert codes(START + "G1 S2000\nPAUSE\nG1 S1000\nPAUSE", test_profile) == []


# --- selection and inline ignores -----------------------------------------------------------------


def test_inline_ignore_silences_only_its_codes_on_its_line():
    script = START + "G1 X260 F30 ; armctl: ignore[L203]\nG1 X270 F30\nG1 X280 F9000 ; armctl: ignore[L203]"
    assert codes(script) == [(3, "L203"), (4, "L201")]


def test_bare_inline_ignore_and_prefixes():
    assert codes(START + "G1 X260 F30 ; armctl: ignore") == []
    assert codes(START + "G1 X260 F30 ; armctl: ignore[E, l2]") == []
    assert codes(START + "G1 X260 F30 ; armctl: ignore[L1]") == [(2, "L203")]


def test_selection_by_code_and_prefix():
    script = START + "G1 X260 F30\nG1 X270 F9000\nG4"
    # a language error (E004: G4 without P) is reported whatever the selection: compile and run
    # refuse the script anyway, so a lint that passed it would be untrue
    assert codes(script, selection=Selection.of(["L2"])) == [(2, "L203"), (3, "L201"), (4, "E004")]
    assert codes(script, selection=Selection.of([], ["L203", "E"])) == [(3, "L201"), (4, "E004")]
    assert codes(START + "G1 X260 F30 ; armctl: ignore\nG4 ; armctl: ignore\n") == [(3, "E004")]


def test_unknown_selection_code_is_refused():
    with pytest.raises(ValueError, match="X999"):
        Selection.of(["X999"])


def test_kept_diagnostics_are_capped_but_all_counted():
    script = START + "".join(f"G1 X{200 + k % 50} F30\n" for k in range(50))
    report = lint(script, max_diagnostics=10)
    assert len(report.diagnostics) == 10
    assert report.counts["L203"] == 50 and report.hidden == 40 and report.warnings == 50
