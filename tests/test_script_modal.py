"""Modal state: what a move keeps from earlier lines, what makes it unknown, G90/G91,
the initial state and from_line ("lines before N run for their state only")."""

from __future__ import annotations

import pytest

from armctl.core.protocol import AccelLinearMove, JointMove, LinearMove
from armctl.script import InitialState, compile_text

POSE = "X1 Y2 Z3 A4 B5 C6"
KNOWN = InitialState(
    pose=(100, 0, 50, 0, 0, 0), joints_deg=(0, 0, 0, 0, 0, 0), pwm_us={1: 1500}, speed_mm_min=3000,
    speed_deg_s=20, accel_mm_s2=500,
)


def run(source, initial=None, **options):
    job = compile_text(source, "t.txt", initial, **options)
    statements = list(job)
    return [s.command for s in statements], [str(d) for d in job.diagnostics], job


def ok(source, initial=None, **options):
    result, diagnostics, _ = run(source, initial, **options)
    assert diagnostics == []
    return result


def test_omitted_pose_words_keep_the_previous_target():
    first, second = ok(f"G1 {POSE} F100 S1000\nG1 Y20 C60")
    assert second == LinearMove(1, 20, 3, 4, 5, 60, 1000, 100)


def test_cartesian_f_is_shared_by_all_cartesian_moves_and_kept():
    result = ok(f"G1 {POSE} F100 S1000\nG220 X2 K10\nG300 X3 R1\nG301 X4 F250\nG1 X5")
    assert [c.speed_mm_min if hasattr(c, "speed_mm_min") else c.speed1_mm_min for c in result] == [100, 100, 100, 250, 250]


def test_f_is_never_mixed_between_families():
    _, diagnostics, _ = run(f"G1 {POSE} F100 S1000\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6")
    assert diagnostics == ["t.txt:2:1: E004 G6 needs F: no earlier move set it"]
    result = ok(f"G6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6 F10 S900\nG1 {POSE}", InitialState(speed_mm_min=3000))
    assert result[0].speed_deg_s == 10 and result[1].speed_mm_min == 3000


def test_f_hint_names_the_other_family():
    job = compile_text(f"G1 {POSE} F100 S1000\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6", "t.txt")
    list(job)
    assert job.diagnostics[0].hint == (
        "write F (deg/s) on this line: Cartesian moves (mm/min) and G6 (deg/s) keep separate speeds")


def test_s_is_kept_per_pwm_channel_and_t_is_modal():
    result, diagnostics, _ = run("G1 T2 S2000\nG1 X5\nG1 T1 X6\nG1 T3 X7", KNOWN)
    assert [(c.pwm_channel, c.pwm_us) for c in result] == [(2, 2000), (2, 2000), (1, 1500)]
    assert diagnostics == ["t.txt:4:1: E004 G1 needs S: no earlier move set it"]


def test_missing_s_of_another_channel_has_a_hint():
    job = compile_text("G1 T3 X7", "t.txt", KNOWN)
    list(job)
    assert job.diagnostics[0].hint == "S is kept per PWM channel; channel 3 has none yet: write S on this line"


def test_joint_moves_and_arcs_use_channel_1s_pwm():
    result = ok("G1 T2 S2000\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6\nG1 T1 S900 X1 Y2 Z3 A0 B0 C0\nG300 X2 R5\nG301 X3", KNOWN)
    assert result[1].pwm_us == 1500
    assert result[3].pwm_us == result[4].pwm_us == 900


def test_k_is_modal_and_h_defaults_to_0_and_is_modal():
    result = ok("G220 X1 K100\nG222 X2\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6\nG6 J1=2 H4\nG6 J1=3", KNOWN)
    assert [result[0].accel_mm_s2, result[1].accel_mm_s2] == [100, 100]
    assert [c.smoothing for c in result[2:]] == [0, 4, 4]


def test_u_v_default_to_0_and_are_modal_across_moves():
    result = ok("G1 X1\nG1 U10 V20\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6\nG1 X1 Y2 Z3 A0 B0 C0\nG300 X2 R1\nG301 X3", KNOWN)
    assert (result[0].e0_deg, result[0].e1_deg) == (0, 0)
    assert all((c.e0_deg, c.e1_deg) == (10, 20) for c in result[1:])


@pytest.mark.parametrize("forgetting, family", [
    ("G6 J1=1", "cartesian"), ("POSE 1", "both"), ("PROGRAM 3", "both"), ("RESET", "both"),
    ("G54 X0 Y0 Z0", "cartesian"), ("G1 X1", "joints"), ("G220 X1", "joints"), ("G300 X1 R1\nG301 X2", "joints"),
])
def test_what_makes_a_target_unknown(forgetting, family):
    _, cartesian, _ = run(f"{forgetting}\nG1 X5", KNOWN)
    _, joints, _ = run(f"{forgetting}\nG6 J1=5", KNOWN)
    lost_cartesian = any("G1 needs Y, Z, A, B, C" in d for d in cartesian)
    lost_joints = any("G6 needs J2, J3, J4, J5, J6" in d for d in joints)
    assert (lost_cartesian, lost_joints) == {"cartesian": (True, False), "joints": (False, True), "both": (True, True)}[family]


def test_reset_connector_pause_and_mode_keep_the_targets():
    ok("RESET CONNECTOR\nPAUSE\nMODE 1\nG1 X5", KNOWN)
    ok("RESET CONNECTOR\nPAUSE\nMODE 1\nG6 J1=5", KNOWN)


def test_unknown_target_hint_names_the_statement_that_lost_it():
    job = compile_text("G6 J1=1\nG1 X5", "t.txt", KNOWN)
    list(job)
    assert str(job.diagnostics[0]) == "t.txt:2:1: E004 G1 needs Y, Z, A, B, C: no earlier move set them"
    assert job.diagnostics[0].hint == (
        "G6 on line 1 left the Cartesian target unknown (the host has no kinematics): write all of X Y Z A B C on this move")


def test_first_move_needs_everything_by_default():
    _, diagnostics, _ = run("G1 X5")
    assert diagnostics == ["t.txt:1:1: E004 G1 needs Y, Z, A, B, C, S, F: no earlier move set them"]


def test_a_complete_first_move_needs_nothing_else():
    assert ok(f"G1 {POSE} S1000 F100") == [LinearMove(1, 2, 3, 4, 5, 6, 1000, 100)]


def test_g91_is_relative_to_the_previous_target_for_pose_joint_and_external_words():
    result = ok(f"G1 {POSE} F100 S1000 U1 V1\nG91\nG1 X10 C-6 U5 F200 S900\nG90\nG6 J1=1 J2=2 J3=3 J4=4 J5=5 J6=6\n"
                "G91\nG6 J1=1 J6=-1 V2 F5\nG90\nG1 X1 Y1 Z1 A1 B1 C1", InitialState(speed_deg_s=1))
    assert result[1] == LinearMove(11, 2, 3, 4, 5, 0, 900, 200, 6, 1)  # F and S are never relative
    assert result[2].joints_deg == (1, 2, 3, 4, 5, 6)
    assert result[3].joints_deg == (2, 2, 3, 4, 5, 5) and result[3].speed_deg_s == 5 and result[3].e1_deg == 3
    assert result[4] == LinearMove(1, 1, 1, 1, 1, 1, 900, 200, 6, 3)


def test_g91_does_not_apply_to_k_q_h_r_p_or_g54():
    result = ok("G91\nG230 X0 K100 Q50 F500\nG230 X0 K100 Q50\nG90\nG6 J1=0 J2=0 J3=0 J4=0 J5=0 J6=0 H2\nG91\n"
                "G6 J1=0 H2\nG90\nG1 X0 Y0 Z0 A0 B0 C0\nG91\nG300 X0 R5\nG301 X0\nG4 P10\nG54 X1 Y2 Z3", KNOWN)
    assert [c.accel_mm_s2 for c in result[:2]] == [100, 100] and [c.speed0_mm_min for c in result[:2]] == [50, 50]
    assert [c.smoothing for c in result[2:4]] == [2, 2]
    assert result[5].radius_mm == 5 and result[7].delay_ms == 10
    assert (result[8].x_mm, result[8].y_mm, result[8].z_mm) == (1, 2, 3)


def test_g91_on_an_unknown_value_is_an_error():
    _, diagnostics, _ = run("G91\nG1 X5 Y1 Z1 A1 B1 C1 F1 S1000")
    assert diagnostics[0] == "t.txt:2:4: E004 X is relative (G91), but no earlier move set X"
    assert len(diagnostics) == 6


def test_arc_points_are_targets_for_the_next_point():
    result = ok("G91\nG300 X10 R5\nG301 X10", KNOWN)
    assert (result[0].x_mm, result[1].x_mm) == (110, 120)


def test_initial_state_seeds_everything_it_names():
    initial = InitialState(
        pose=(1, 2, 3, 4, 5, 6), joints_deg=(7, 8, 9, 10, 11, 12), pwm_us={1: 600, 3: 700}, pwm_channel=3,
        speed_mm_min=10, speed_deg_s=11, accel_mm_s2=12, external_deg=(13, 14), smoothing=5, relative=True,
        parameters={"Step": 2},
    )
    result = ok("G1 X#<step>\nG1 T1 Y0\nG220 Z0", initial)
    assert result[0] == LinearMove(3, 2, 3, 4, 5, 6, 700, 10, 13, 14, 3)
    assert result[1] == LinearMove(3, 2, 3, 4, 5, 6, 600, 10, 13, 14, 1)
    assert result[2].accel_mm_s2 == 12 and result[2].z_mm == 3
    assert ok("G6 J1=0", initial) == [JointMove(7, 8, 9, 10, 11, 12, 600, 11, 13, 14, 5)]


def test_initial_state_may_know_part_of_the_pose():
    _, diagnostics, _ = run("G1 X1", InitialState(pose=(1, 2, 3, None, None, None), pwm_us={1: 900}, speed_mm_min=5))
    assert diagnostics == ["t.txt:1:1: E004 G1 needs A, B, C: no earlier move set them"]


@pytest.mark.parametrize("bad", [dict(pose=(1, 2)), dict(pwm_channel=5), dict(pwm_us={0: 1500})])
def test_initial_state_rejects_nonsense(bad):
    with pytest.raises(ValueError):
        InitialState(**bad)


def test_final_state_snapshot_resumes_where_the_script_left_off():
    _, _, job = run(f"G1 {POSE} F100 S1000 T2\n#<n> = 4\nG91", KNOWN)
    snapshot = job.state.snapshot()
    assert snapshot.pose == (1, 2, 3, 4, 5, 6) and snapshot.joints_deg is None
    assert snapshot.pwm_us == {1: 1500, 2: 1000} and snapshot.pwm_channel == 2
    assert snapshot.relative and snapshot.parameters == {"n": 4}
    assert ok("G1 X1", snapshot) == [LinearMove(2, 2, 3, 4, 5, 6, 1000, 100, 0, 0, 2)]


def test_from_line_runs_earlier_lines_for_their_state_only():
    source = "#<a> = 7\nG1 X1 Y2 Z3 A0 B0 C0 F100 S900\nG91\nG1 X#<a>\nG1 X1"
    job = compile_text(source, "t.txt", from_line=4)
    statements = list(job)
    assert [s.line for s in statements] == [4, 5]
    assert [s.command.x_mm for s in statements] == [8, 9]
    assert job.ok


def test_from_line_counts_repeat_blocks_before_it():
    source = "#<x> = 0\nO<a> repeat [3]\n#<x> = [#<x> + 1]\nO<a> endrepeat\nG1 X#<x>"
    statements = list(compile_text(source, "t.txt", KNOWN, from_line=5))
    assert [s.command.x_mm for s in statements] == [3]


def test_from_line_at_a_repeat_line_runs_the_whole_block():
    statements = list(compile_text("G1 X0\nO<a> repeat [2]\nG1 X1\nO<a> endrepeat", "t.txt", KNOWN, from_line=2))
    assert [s.loop for s in statements] == [(0,), (1,)]


def test_from_line_must_be_positive():
    with pytest.raises(ValueError):
        compile_text("G1", "t.txt", from_line=0)


def test_statements_record_relative_mode():
    job = compile_text("G1 X1\nG91\nG1 X1", "t.txt", KNOWN)
    assert [s.relative for s in job] == [False, True]


def test_accelerated_move_keeps_q_only_on_g230():
    assert ok("G230 X1 Q5\nG222 X2", KNOWN)[1] == AccelLinearMove(1, 2, 0, 50, 0, 0, 0, 500, 3000)


def test_g222_and_g230_refuse_a_k_that_is_not_positive_even_a_modal_one():
    from armctl.script import compile_text

    job = compile_text("G220 X1 K-100\nG222 X2\nG230 X3 K0 Q10\nG222 X4 K50", "k.txt", KNOWN)
    commands = [s.command for s in job]
    assert [c.accel_mm_s2 for c in commands] == [-100, 50]  # G220 takes a falling ramp
    assert [(d.code, d.span.line) for d in job.diagnostics] == [("E005", 2), ("E005", 3)]
    assert "K = -100 must be greater than 0 in G222" in job.diagnostics[0].message
    assert "K is modal" in job.diagnostics[0].hint
    assert job.diagnostics[1].span.column == job.diagnostics[1].span.text.index("K0") + 1
