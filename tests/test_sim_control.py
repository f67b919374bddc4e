"""The simulated arm's control frames in virtual time: pause in both H5 modes, arm and
connector reset, arcs, fixed poses, SD programs, the joystick, worktable origin, structure mode."""

from __future__ import annotations

import math

import pytest

from armctl.core.motion import MotionModel, arc_through
from armctl.host.profile import default_profile
from armctl.core.protocol import (
    ArcEnd,
    ArcStart,
    Delay,
    FileLengthStatus,
    FileStatus,
    GoToPose,
    Joystick,
    LinearMove,
    MCode,
    PauseStatus,
    PauseToggle,
    PositionStatus,
    ResetArm,
    ResetConnector,
    RunPositionStatus,
    RunProgram,
    SetWorktableOrigin,
    StatusReader,
    StructureMode,
    WorktableStatus,
)
from armctl.sim.model import SimOptions, SimulatedArm
from armctl.sim.program import PROGRAM_RUN_S, STATUS_FINISHED, STATUS_RUNNING, STATUS_STOPPED

PROFILE = default_profile()
ARRIVAL = SimOptions(control_frames="arrival")


def send(arm, *commands, at_s=None):
    """Write the frames at ``at_s`` (default: the model's now); returns when the last one lands."""
    at_s = arm.now_s if at_s is None else at_s
    arm.advance(at_s)
    arm.write(b"".join(c.encode() for c in commands), at_s)
    return max(at_s, arm.host_line_free_s())


def down_move(arm, depth_mm=100.0, speed_mm_min=600.0):
    """A straight move down from where the arm rests (10 mm/s by default)."""
    c = arm.pose.cartesian
    return LinearMove(c.x_mm, c.y_mm, c.z_mm - depth_mm, *c[3:], 1500, speed_mm_min)


def outcomes(arm):
    return [(type(e.command).__name__, e.outcome) for e in arm.execution_log]


# --- pause (H5 queued, the default) ---------------------------------------------------------------


def test_h5_pause_waits_in_the_fifo_and_takes_effect_between_commands():
    arm = SimulatedArm()
    send(arm, Delay(1000), PauseToggle(), Delay(1000))
    arm.advance(0.5)
    assert not arm.paused  # the pause frame landed at 0.1 s but waits behind the delay
    arm.advance(3.0)
    assert arm.paused
    assert outcomes(arm) == [("Delay", "done"), ("PauseToggle", "done")]
    assert arm.execution_log[1].start_s == pytest.approx(1.05)
    assert arm.fifo_occupancy == 1  # the second delay waits


def test_h5_resume_at_the_head_continues_with_the_next_frames():
    arm = SimulatedArm()
    send(arm, Delay(1000), PauseToggle())
    arm.advance(2.0)
    assert arm.paused
    landed_s = send(arm, PauseToggle(), Delay(500), at_s=3.0)
    arm.advance_until_idle()
    assert not arm.paused
    resume, delay = arm.execution_log[2:]
    assert resume.start_s == pytest.approx(3.05)
    assert delay.start_s == pytest.approx(landed_s) and delay.end_s == pytest.approx(landed_s + 0.5)


def test_h5_a_resume_queued_behind_other_frames_never_reaches_the_head():
    arm = SimulatedArm()
    send(arm, PauseToggle(), Delay(100), PauseToggle())
    arm.advance(10.0)
    assert arm.paused and arm.fifo_occupancy == 2
    assert outcomes(arm) == [("PauseToggle", "done")]


def test_h5_pause_status_reports_paused():
    arm = SimulatedArm()
    reader = StatusReader()
    frames = reader.feed(arm.advance(0.5))
    arm.write(PauseToggle().encode(), 0.5)
    frames += reader.feed(arm.advance(1.0))
    pauses = [f.paused for f in frames if isinstance(f, PauseStatus)]
    assert pauses[0] is False and pauses[-1] is True


# --- pause (control frames act on arrival) -----------------------------------------------------


def test_on_arrival_pause_stops_mid_segment_and_resume_continues_where_it_stopped():
    arm = SimulatedArm(ARRIVAL)
    send(arm, down_move(arm))  # 10 s from 0.05 s
    start_z = arm.pose.cartesian.z_mm
    send(arm, PauseToggle(), at_s=1.95)  # lands at 2.0 s
    arm.advance(2.0)
    assert arm.paused
    frozen = arm.pose.cartesian.z_mm
    assert frozen == pytest.approx(start_z - 10 * 1.95, abs=1e-6)
    arm.advance(5.0)
    assert arm.pose.cartesian.z_mm == frozen
    assert StatusReader().feed(arm.advance(5.5))[-1]  # status keeps flowing while paused
    send(arm, PauseToggle(), at_s=5.95)  # resumes at 6.0 s: 4 s paused
    arm.advance_until_idle()
    move = arm.execution_log[0]
    assert move.outcome == "done"
    assert move.end_s == pytest.approx(0.05 + 10 + 4.0)
    assert arm.pose.cartesian.z_mm == pytest.approx(start_z - 100)


def test_on_arrival_control_frames_take_no_fifo_slot():
    arm = SimulatedArm(ARRIVAL)
    send(arm, Delay(100_000), *([Delay(1)] * 200))
    send(arm, PauseToggle(), PauseToggle())
    arm.advance(20.0)
    assert arm.frames_dropped == 0 and arm.fifo_occupancy == 200
    assert [f.accepted for f in arm.frames_received[-2:]] == [True, True]


# --- resets -------------------------------------------------------------------------------------


def test_h5_arm_reset_acts_at_the_head_and_keeps_frames_that_landed_after_it():
    arm = SimulatedArm()
    send(arm, Delay(1000), ResetArm(), Delay(500))
    arm.advance_until_idle()
    assert outcomes(arm) == [("Delay", "done"), ("ResetArm", "done"), ("Delay", "done")]
    assert arm.execution_log[1].start_s == pytest.approx(1.05)


def test_on_arrival_arm_reset_stops_the_move_where_it_is_and_drops_the_waiting_frames():
    arm = SimulatedArm(ARRIVAL)
    start_z = arm.pose.cartesian.z_mm
    send(arm, down_move(arm), MCode(1), MCode(2))
    send(arm, ResetArm(), at_s=1.95)  # lands at 2.0 s
    landed_s = send(arm, MCode(3), at_s=3.0)
    arm.advance_until_idle()
    assert outcomes(arm) == [("LinearMove", "interrupted"), ("ResetArm", "done"), ("MCode", "done")]
    assert arm.execution_log[0].end_s == pytest.approx(2.0)
    assert arm.execution_log[2].command == MCode(3) and arm.execution_log[2].start_s == pytest.approx(landed_s)
    assert arm.connector.cleared_indexes == [1, 2]
    assert arm.pose.cartesian.z_mm == pytest.approx(start_z - 10 * 1.95, abs=1e-6)
    assert not arm.busy


def test_arm_reset_clears_pause_on_arrival():
    arm = SimulatedArm(ARRIVAL)
    send(arm, PauseToggle(), ResetArm())
    arm.advance(1.0)
    assert not arm.paused


def test_h5_connector_reset_flushes_the_frames_behind_it():
    arm = SimulatedArm()
    send(arm, Delay(1000), ResetConnector(), MCode(1), MCode(2))
    arm.advance_until_idle()
    assert outcomes(arm) == [("Delay", "done"), ("ResetConnector", "done")]
    assert arm.connector.cleared_indexes == [2, 3]
    assert arm.fifo_occupancy == 0


def test_on_arrival_connector_reset_flushes_the_fifo_but_the_running_frame_finishes():
    arm = SimulatedArm(ARRIVAL)
    send(arm, Delay(1000), MCode(1), MCode(2), ResetConnector())
    arm.advance_until_idle()
    assert outcomes(arm) == [("Delay", "done"), ("ResetConnector", "done")]
    assert arm.execution_log[0].end_s == pytest.approx(1.05)
    assert arm.connector.cleared_indexes == [1, 2]


# --- arcs ----------------------------------------------------------------------------------------


def test_an_arc_start_waits_for_its_arc_end_and_both_run_as_one_arc():
    arm = SimulatedArm()
    c = arm.pose.cartesian
    via = ArcStart(c.x_mm + 30, c.y_mm + 30, c.z_mm, *c[3:], 1500, 30, 1800)
    end = ArcEnd(c.x_mm, c.y_mm + 60, c.z_mm, *c[3:], 1500, 1800)
    send(arm, via)
    arm.advance(2.0)
    assert arm.execution_log == [] and not arm.busy  # the G300 waits at the head
    landed_s = send(arm, end, at_s=2.0)
    arm.advance(landed_s)
    segment = MotionModel(PROFILE).plan(end, MotionModel(PROFILE).initial_pose(), arc_start=via)
    first, second = arm.execution_log
    assert first.start_s == second.start_s == pytest.approx(landed_s)
    arc = arc_through(c[:3], (via.x_mm, via.y_mm, via.z_mm), (end.x_mm, end.y_mm, end.z_mm))
    for fraction in (0.25, 0.5, 0.75):
        arm.advance(landed_s + fraction * segment.duration_s)
        point = arm.pose.cartesian[:3]
        assert math.dist(point, arc.center) == pytest.approx(arc.radius_mm, abs=1e-6)
    assert len(arm.connector.executing) == 2 and arm.fifo_occupancy == 0  # both taken together, as one
    arm.advance_until_idle()
    assert first.end_s == second.end_s == pytest.approx(landed_s + segment.duration_s)
    assert arm.pose.cartesian[:3] == pytest.approx((end.x_mm, end.y_mm, end.z_mm))
    assert arm.fifo_occupancy == 0


def test_an_arc_start_not_followed_by_its_arc_end_is_skipped():
    arm = SimulatedArm()
    c = arm.pose.cartesian
    send(arm, ArcStart(c.x_mm + 30, c.y_mm + 30, c.z_mm, *c[3:], 1500, 30, 1800), Delay(100))
    arm.advance_until_idle()
    assert outcomes(arm) == [("ArcStart", "skipped"), ("Delay", "done")]


# --- fixed poses and SD programs ----------------------------------------------------------------


@pytest.mark.parametrize("pose", [1, 2, 3])
def test_go_to_a_fixed_pose_is_a_joint_move_there(pose):
    arm = SimulatedArm()
    landed_s = send(arm, GoToPose(pose))
    arm.advance_until_idle()
    expected_s = MotionModel(PROFILE).plan(GoToPose(pose), MotionModel(PROFILE).initial_pose()).duration_s
    entry = arm.execution_log[0]
    assert entry.start_s == pytest.approx(landed_s)
    assert entry.duration_s == pytest.approx(expected_s)
    assert arm.pose.joints == pytest.approx(PROFILE.poses[pose])


def test_an_sd_program_reports_its_file_and_a_run_position_that_advances():
    arm = SimulatedArm()
    landed_s = send(arm, RunProgram(3), MCode(1))
    reader = StatusReader()
    frames = reader.feed(arm.advance(landed_s + 2.0))
    assert arm.busy and arm.program.status_at(arm.now_s) == STATUS_RUNNING
    length = [f.value for f in frames if isinstance(f, FileLengthStatus)][-1]
    assert length == 1300.0
    assert [f.raw for f in frames if isinstance(f, FileStatus)][-1] == STATUS_RUNNING
    positions = [f.value for f in frames if isinstance(f, RunPositionStatus)]
    assert positions == sorted(positions) and 0 < positions[-1] < 1300
    assert positions[-1] == pytest.approx(1300 * 2.0 / PROGRAM_RUN_S, abs=1300 * 0.3 / PROGRAM_RUN_S)
    frames = reader.feed(arm.advance(landed_s + PROGRAM_RUN_S + 0.5))
    assert [f.raw for f in frames if isinstance(f, FileStatus)][-1] == STATUS_FINISHED
    assert [f.value for f in frames if isinstance(f, RunPositionStatus)][-1] == 1300.0
    program, mcode = arm.execution_log
    assert program.duration_s == pytest.approx(PROGRAM_RUN_S)
    assert mcode.start_s == pytest.approx(program.end_s)  # the program held the arm


def test_an_arm_reset_stops_an_sd_program_on_arrival():
    arm = SimulatedArm(ARRIVAL)
    send(arm, RunProgram(0))
    send(arm, ResetArm(), at_s=1.0)
    arm.advance(2.0)
    assert arm.program.status_at(arm.now_s) == STATUS_STOPPED
    assert 0 < arm.program.position_at(arm.now_s) < 1000


def test_an_sd_program_pauses_with_the_arm_on_arrival():
    arm = SimulatedArm(ARRIVAL)
    landed_s = send(arm, RunProgram(1))
    send(arm, PauseToggle(), at_s=landed_s + 0.95)  # lands 1 s into the program
    arm.advance(landed_s + 3.0)
    assert arm.program.position_at(arm.now_s) == pytest.approx(1100 * 1.0 / PROGRAM_RUN_S)
    send(arm, PauseToggle(), at_s=landed_s + 4.95)  # 4 s paused
    arm.advance_until_idle()
    assert arm.execution_log[0].end_s == pytest.approx(landed_s + PROGRAM_RUN_S + 4.0)
    assert arm.program.status_at(arm.now_s) == STATUS_FINISHED


# --- joystick ------------------------------------------------------------------------------------


def test_the_joystick_turns_a_joint_while_off_centre_and_stops_on_neutral():
    arm = SimulatedArm()
    landed_s = send(arm, Joystick(0, (200,)))
    rate_deg_s = (200 - 128) / 127 * PROFILE.speed.max_joint_deg_s
    arm.advance(landed_s + 0.5)
    assert arm.pose.joints[0] == pytest.approx(0.5 * rate_deg_s)
    stopped_s = send(arm, Joystick(0, (140,)), at_s=landed_s + 0.95)  # 140: inside the still band
    arm.advance(stopped_s)
    stopped_at = arm.pose.joints[0]
    assert stopped_at == pytest.approx((stopped_s - landed_s) * rate_deg_s)
    arm.advance(stopped_s + 2.0)
    assert arm.pose.joints[0] == stopped_at


def test_the_joystick_turns_the_other_way_below_the_still_band_and_stops_at_the_limit():
    arm = SimulatedArm()
    send(arm, Joystick(1, (0,)))
    arm.advance(10.0)
    assert arm.pose.joints[1] == PROFILE.joint_limits_deg[1][0]
    frames = StatusReader().feed(arm.advance(10.3))
    reported = [f.j2_deg for f in frames if f.KIND == 1]
    assert reported and set(reported) == {PROFILE.joint_limits_deg[1][0]}


def test_the_linear_joystick_moves_the_tool_along_z_and_stops_on_neutral():
    arm = SimulatedArm()
    start = arm.pose.cartesian
    landed_s = send(arm, Joystick(100, (128, 128, 60)))
    rate_mm_s = (60 - 128) / 127 * PROFILE.speed.max_linear_mm_min / 60
    arm.advance(landed_s + 0.5)
    now = arm.pose.cartesian
    assert now.z_mm == pytest.approx(start.z_mm + 0.5 * rate_mm_s, abs=1e-3)
    assert now.x_mm == pytest.approx(start.x_mm, abs=1e-3)
    stopped_s = send(arm, Joystick(100, (128, 128, 128)))
    arm.advance(stopped_s)
    held = arm.pose.cartesian
    arm.advance(stopped_s + 1.0)
    assert arm.pose.cartesian == pytest.approx(held)


def test_the_joystick_is_slower_on_a_slower_arm_and_ignored_while_paused_on_arrival():
    arm = SimulatedArm(SimOptions(control_frames="arrival", speed_factor=2.0))
    landed_s = send(arm, Joystick(0, (255,)))
    arm.advance(landed_s + 1.0)
    assert arm.pose.joints[0] == pytest.approx(PROFILE.speed.max_joint_deg_s / 2.0)
    send(arm, PauseToggle(), Joystick(1, (255,)))
    arm.advance(arm.now_s + 1.0)
    assert arm.paused and arm.pose.joints[1] == 0.0
    assert outcomes(arm)[-2:] == [("PauseToggle", "done"), ("Joystick", "ignored")]


def test_a_queued_motion_frame_stops_the_joystick():
    arm = SimulatedArm()
    send(arm, Joystick(0, (255,)), Delay(100))
    arm.advance(1.0)
    assert arm.pose.joints[0] == pytest.approx(0.05 * PROFILE.speed.max_joint_deg_s, rel=1e-3)


# --- worktable origin and structure mode ------------------------------------------------------


def test_the_worktable_origin_shifts_commands_and_reported_positions():
    arm = SimulatedArm()
    robot = arm.pose.robot_cartesian
    send(arm, SetWorktableOrigin(10, 20, 30))
    arm.advance(0.2)
    assert arm.snapshot().position_mm == pytest.approx((robot.x_mm - 10, robot.y_mm - 20, robot.z_mm - 30))
    send(arm, LinearMove(190, -10, 200, 180, 0, 0, 1500, 3000))
    arm.advance_until_idle()
    assert arm.pose.robot_cartesian[:3] == pytest.approx((200, 10, 230))
    frames = {f.KIND: f for f in StatusReader().feed(arm.advance(arm.now_s + 0.3))}
    assert frames[3] == WorktableStatus(10, 20, 30)
    assert frames[0] == PositionStatus(190, -10, 200)


def test_structure_mode_is_recorded():
    arm = SimulatedArm()
    send(arm, StructureMode(1))
    arm.advance(0.1)
    assert arm.structure_mode == 1
