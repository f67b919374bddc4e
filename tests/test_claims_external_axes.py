"""Issue 22: a move of the external axes alone (E0/E1: ``U``/``V``) is no loss.

The motion model gives such a move its time (a joint move's lead is E0/E1's when no joint
turns), and the simulator runs it for that time — but no status kind reports E0/E1, so every
reading stays still while it runs.  The one fact both sides read is the model's
``Segment.moves_reported``: the job engine's end of motion (where the arm was last seen moving,
then the model's time of the frames that leave no trace) counts such a move among the frames
that leave no trace, so the arm time runs to its end and nothing is claimed lost.  Before, the
healthy simulator's run of ``G6 … U250 F20`` ended "frames may have been lost" (arm time 0.1 s
against 12.6 s estimated).  Virtual time; the installed command in a fresh process, and the API.
"""

from __future__ import annotations

import re
import subprocess

import pytest

from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import JointMove, LinearMove
from claims_common import fresh

U_ONLY = "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 U250 S1500 F20\n"


def _run(tmp_path, script: str) -> subprocess.CompletedProcess:
    (tmp_path / "job.txt").write_text(script, encoding="utf-8")
    return fresh(["-m", "armctl", "run", "job.txt", "--no-live", "--port", "sim://?clock=virtual"], tmp_path, timeout_s=40)


@pytest.mark.parametrize("script", [
    U_ONLY,
    "G1 X250 Y0 Z150 A180 B0 C0 S1500 F6000\nG6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 V120 F30\n",  # after a move, at the end
    U_ONLY + "G6 J1=10 F30\nG6 U0 F60\nG6 J1=0 F30\n",  # in the middle of a job
], ids=["u-only", "v-only-last", "u-only-between"])
def test_a_move_of_the_external_axes_alone_ends_done_with_its_time(tmp_path, script):
    result = _run(tmp_path, script)
    assert result.returncode == 0, (result.stdout, result.stderr)
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert "lost" not in result.stdout + result.stderr
    arm_s, estimated_s = map(float, re.search(r"arm time: ([\d.]+) s .*estimated ([\d.]+) s", result.stdout).groups())
    assert abs(arm_s - estimated_s) <= 0.05 * estimated_s + 0.3, result.stdout


def test_arm_move_of_an_external_axis_through_the_api(tmp_path):
    program = ("from armctl import Arm\n"
               "with Arm.open(port='sim://?clock=virtual') as arm:\n"
               "    r = arm.move(j1=0, j2=0, j3=0, j4=0, j5=90, j6=0, u=250, f=20)\n"
               "    print(r.outcome, round(r.arm_time_s, 1), round(r.estimated_job_s, 1))\n")
    result = fresh(["-c", program], tmp_path, timeout_s=40)
    outcome, arm_s, estimated_s = result.stdout.split()
    assert outcome == "finished" and abs(float(arm_s) - float(estimated_s)) < 0.7, (result.stdout, result.stderr)


def test_the_model_says_which_motion_the_reports_show():
    model = MotionModel(load_profile())
    start = model.initial_pose()
    joints = tuple(start.joints)
    u_only = model.plan(JointMove(*joints, pwm_us=1500, e0_deg=250, speed_deg_s=20), start)
    assert u_only.duration_s > 12 and u_only.length == 250  # the arm takes its time …
    assert not u_only.moves_reported  # … and no status shows it
    turning = model.plan(JointMove(joints[0] + 5, *joints[1:], pwm_us=1500, e0_deg=250, speed_deg_s=20), start)
    assert turning.moves_reported
    x, y, z, b0, b1, w = start.cartesian
    assert not model.plan(LinearMove(x, y, z, b0, b1, w, pwm_us=1500, e0_deg=90, speed_mm_min=3000), start).moves_reported
    assert model.plan(LinearMove(x + 5, y, z, b0, b1, w, pwm_us=1500, speed_mm_min=3000), start).moves_reported
