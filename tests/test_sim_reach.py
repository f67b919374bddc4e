"""The simulated arm cannot go where it cannot go (issue 24): a target outside its own reach —
by its own kinematics, ``link_scale`` included — or its joint limits is refused, as a controller
refuses an IK failure, so a job holding one never ends "finished" (armctl/sim/executor.py, "Reach")."""

import json
import subprocess
import sys

import pytest

from armctl.core.protocol import JointMove, LinearMove
from armctl.sim.executor import DONE, REFUSED
from armctl.sim.model import SimOptions, SimulatedArm

START = LinearMove(250, 0, 250, 180, 0, 0, 1500, 6000)


def _run(arm: SimulatedArm, *commands) -> None:
    for command in commands:
        arm.write(command.encode(), arm.now_s)
    arm.advance_until_idle(600.0)


def _outcomes(arm: SimulatedArm) -> list[str]:
    return [e.outcome for e in arm.execution_log]


def test_a_target_two_metres_away_is_refused_and_the_arm_stays_where_it_was():
    arm = SimulatedArm(SimOptions())
    _run(arm, START, LinearMove(2000, 0, 250, 180, 0, 0, 1500, 6000))
    assert _outcomes(arm) == [DONE, REFUSED]
    assert arm.snapshot().position_mm == pytest.approx((250, 0, 250), abs=1e-6)
    assert "out of the arm's reach" in arm.execution_log[-1].note


def test_joint_targets_outside_the_limits_are_refused():
    arm = SimulatedArm(SimOptions())
    low, high = arm.profile.joint_limits_deg[0]
    _run(arm, JointMove(high + 10, 0, 0, 0, 90, 0, 1500, 20), JointMove(0, 0, 0, 0, 90, 0, 1500, 20))
    assert _outcomes(arm) == [REFUSED, DONE]
    assert "J1" in arm.execution_log[0].note


def test_the_arms_own_links_decide_not_the_profiles():
    """A target near the edge of the profile's reach: taken by an arm with the profile's links,
    refused by one whose links are 20 % shorter."""
    edge = LinearMove(0, 0, 0, 180, 0, 0, 1500, 6000)
    profile_arm = SimulatedArm(SimOptions())
    reach_mm = profile_arm.profile.workspace.reach_mm
    for x_mm in range(int(reach_mm), 100, -10):  # the farthest straight-out target the profile's arm takes
        edge = LinearMove(x_mm, 0, 250, 180, 0, 0, 1500, 6000)
        arm = SimulatedArm(SimOptions())
        _run(arm, START, edge)
        if _outcomes(arm)[-1] == DONE:
            break
    else:
        pytest.fail("no reachable target straight out")
    short = SimulatedArm(SimOptions(link_scale=0.8))
    _run(short, START, edge)
    assert _outcomes(short)[-1] == REFUSED


@pytest.mark.timeout(60)
def test_armctl_run_of_a_2_m_move_never_ends_finished(tmp_path):
    """Through the installed command in a fresh process (lint may refuse it first: either way the
    arm is never said to have finished it)."""
    job = tmp_path / "far.txt"
    job.write_text("G90\nG1 X250 Y0 Z250 A180 B0 C0 S1500 F6000\nG1 X2000\n")
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(job), "--port", "sim://?clock=virtual",
                           "--no-live", "--json"], capture_output=True, text=True, timeout=60)
    assert done.returncode in (1, 2), done.stderr
    assert "Traceback" not in done.stderr
    outcomes = [json.loads(line).get("outcome") for line in done.stdout.splitlines() if line.startswith("{")]
    assert "finished" not in outcomes, done.stdout


# A target lint only warns about (the built-in profile's workspace is illustrative) but the arm
# cannot take, between two it can: the simulator refuses it and runs on to the next, from where
# it stands.  Found by the README audit (wt-readme): pick_and_place.txt with its first X250 made
# X500 ended "finished", exit 0 — the time bound counted the refused moves done while the arm's
# reports showed it standing at their start.
REFUSED_MID_JOB = "G90\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X500\nG1 X250 Y100\n"


def test_a_refused_target_mid_job_is_never_finished_in_process():
    from armctl import Arm, JobFailed

    with Arm.open("sim://?clock=virtual") as arm:
        try:
            result = arm.run(REFUSED_MID_JOB)
        except JobFailed as failed:
            result = failed.result
    assert result.outcome != "finished" and result.exit_code == 1, result
    assert result.last_line_executed is None or result.last_line_executed < 3, result


@pytest.mark.timeout(60)
def test_armctl_run_of_a_refused_target_mid_job_exits_1(tmp_path):
    job = tmp_path / "reach.txt"
    job.write_text(REFUSED_MID_JOB)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(job), "--port", "sim://?clock=virtual",
                           "--no-live", "--json"], capture_output=True, text=True, timeout=60)
    assert "Traceback" not in done.stderr
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 1 and summary["outcome"] != "finished", (done.stdout, done.stderr)


# The sign itself, hand-fed (armctl/core/streamer/losses.py ``check_not_begun``): the arm at the
# start of a long move after its time bound.  A pause that holds it there is not the sign.
def _streamer_with_one_long_move():
    from armctl.core.motion import MotionModel
    from armctl.core.streamer import Streamer
    from armctl.host.profile import default_profile

    model = MotionModel(default_profile())
    pose = model.initial_pose()
    streamer = Streamer(model, model.reported_pose(pose.xyz, pose.joints, 1500.0, (0.0, 0.0, 0.0)))
    sent = streamer.wrote(LinearMove(250, 0, 150, 180, 0, 0, 1500, 600), 0.0)  # about 16 s of motion
    return streamer, sent, pose.xyz


def _feed(streamer, xyz, paused: bool, from_s: float, to_s: float) -> None:
    from armctl.core.protocol import PauseStatus, PositionStatus

    now = from_s
    while now < to_s:
        streamer.receive_status(PositionStatus(*xyz), now)
        streamer.receive_status(PauseStatus(1 if paused else 0, 1500), now + 0.12)
        now += 0.27


def test_the_arm_standing_at_the_start_of_a_move_past_its_time_bound_is_a_sign_of_loss():
    streamer, sent, home = _streamer_with_one_long_move()
    _feed(streamer, home, False, 0.03, sent.certain_end_s + 1.0)
    assert len(streamer.losses) == 1 and "stood at the start of" in streamer.losses[0], streamer.losses
    assert streamer.first_suspect_index == sent.index


def test_nor_is_a_pause_that_holds_the_arm_at_the_start():
    streamer, sent, home = _streamer_with_one_long_move()
    _feed(streamer, home, False, 0.03, 1.0)
    _feed(streamer, home, True, 1.0, sent.certain_end_s + 10.0)  # paused before it began, and held
    assert streamer.losses == [] and streamer.pending
