"""Cartesian moves from a joint move's end on an arm whose kinematics are not verified: where they
start only the arm's own kinematics know, so they may be longer or shorter than planned — and joint
moves from a Cartesian move's end, whose start joints only the arm's own IK knows.

Jobs Hypothesis found for the random-jobs property of tests/test_connector_settings.py, kept as
explicit cases: an arc (G300/G301) right after a joint move.  The arc's real start is where the arm's own kinematics put the joint move's end, and
the circle through it, the G300 point and the end may be far longer than the planned one — so
the time bound never confirms such an arc (``TimeBound.allowance_s``); a sighting on a later
frame does, or the arm at rest at the last target, which the job engine also applies mid-job
while the FIFO bound holds the next frame (``Job._rest_proves_all_written``)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from armctl.host.profile import parse_profile
from armctl.core.protocol import ArcEnd, ArcStart, Delay, JointMove, LinearMove, MCode, SetWorktableOrigin
from tests.test_connector_settings import check_job, check_random_job
from tests.test_streamer_sim import POINTS, _joints

# Found on main (58fb5c8): the lower bound passed what the simulated arm had really finished
# (7 claimed, 5 finished, from t = 76.8 s) — the time bound allowed 10 % of the reach of extra
# path at the G301's feed, and the planned arc was 571 mm.
OVERSTATED = dict(
    ops=[("line", 4, 6000.0), ("pwm", 1000.0), ("line", 0, 600.0), ("joint", 5, 30.0, 0), ("arc", 0, 5),
         ("pwm", 2000.0), ("joint", 2, 30.0, 2), ("delay", 0.0), ("delay", 0.0), ("mcode", 107),
         ("joint", 3, 90.0, 6), ("joint", 4, 90.0, 0), ("pwm", 2000.0), ("arc", 0, 5)],
    fifo=200, control="queued", frame="worktable", speed_factor=2.0, link_scale=1.05,
    origin=(10.0, -20.0, 5.0), damage=0.0, seed=47,
)
# Found with the arc left unconfirmed by time: a FIFO of 8 full of the arc and the PWM frames
# after it, which only time could confirm — the job waited for ever.  The arm at rest at the last
# target (its FIFO drained) proves them all; the estimate must not stay on the held G300 (whose
# joints 4-6 the arm still reports at the arc's end) or the rest is never judged over.
HELD_BY_THE_FIFO_BOUND = dict(
    ops=[("line", 0, 600.0), ("pwm", 1000.0), ("joint", 5, 30.0, 0), ("arc", 0, 5), ("pwm", 1000.0),
         ("pwm", 1000.0), ("turn", 45.0)],
    fifo=8, control="queued", frame="worktable", speed_factor=0.7, link_scale=1.0,
    origin=None, damage=0.1, seed=633,
)

# Found on 9f6098f (shrunk from Hypothesis' case): held after the arc, the arm at rest at the last
# target (the end of the accelerated move), but the PWM frame at the arc's end counted as a place
# the arm rests before the last move (``Job._resting_before_last_move``) though it rests 100 mm
# from that target — only a rest that may read as the last target proves nothing.
HELD_BY_A_REST_FAR_FROM_THE_TARGET = dict(
    ops=[("joint", 0, 90.0, 3), ("arc", 1, 2), ("pwm", 1000.0), ("accel", 3, 1), ("pose", 2)],
    fifo=200, control="arrival", frame="worktable", speed_factor=2.0, link_scale=1.0,
    origin=None, damage=0.0, seed=353, speed_tolerance=1.05,
)
# The same, but the job comes back to the arc's end while held there, so at rest at the last
# target may be at rest in the PWM frame before it: that rest proves only the frames before that
# frame (the arc among them; ``Job._rest_proves_done_before``), then time confirms the rest.  It
# waited for ever before.
HELD_BY_A_REST_AT_THE_TARGET = dict(
    ops=[("joint", 0, 90.0, 3), ("arc", 1, 2), ("pwm", 1000.0), ("line", 5, 6000.0), ("line", 2, 6000.0),
         ("pose", 2)],
    fifo=200, control="arrival", frame="worktable", speed_factor=2.0, link_scale=1.0,
    origin=None, damage=0.0, seed=353, speed_tolerance=1.05,
)
# Found so by a 4,000-example run of the property (a wrist turn after the PWM frame, at the arc's
# end X/Y/Z, which is where the joint move before the arc ended too).
HELD_BY_A_REST_AT_THE_TARGET_AFTER_A_TURN = dict(
    ops=[("joint", 0, 30.0, 0), ("arc", 2, 0), ("pwm", 1000.0), ("turn", 90.0), ("line", 0, 600.0), ("line", 0, 600.0)],
    fifo=8, control="queued", frame="worktable", speed_factor=2.0, link_scale=1.0,
    origin=None, damage=0.1, seed=999,
)

# Found on d4b9cc9 (a 4,000-example run of the property, shrunk by Hypothesis): the other way round,
# a joint move from a Cartesian move's end, on an arm with links 5 % short: the joint move to the
# joints the profile's IK gives for that end was planned 0 s long, while the arm (its own IK put it
# elsewhere) still had to turn; at the probe's speed_tolerance 1.05 the time bound claimed it done
# (2 claimed, 1 finished at 39.8 s).  Its allowance: anywhere within the joint limits.
JOINT_MOVE_FROM_A_CARTESIAN_END = dict(
    ops=[("line", 1, 600.0), ("joint", 1, 30.0, 0)],
    fifo=8, control="queued", frame="worktable", speed_factor=2.0, link_scale=0.95,
    origin=None, damage=0.0, seed=0, speed_tolerance=1.05,
)

# Found so too: an arc whose end is the joint move's end (the planned circle through start, G300
# point and end degenerates, so the plan makes it a line of length 0) — time confirmed it at once
# (3 claimed, 1 finished at 2.56 s) while the arm, from its real start, ran a whole arc.  Any G301
# from an unverified joint end now counts as an arc: time never confirms it.
ARC_PLANNED_AS_A_LINE = dict(
    ops=[("joint", 2, 30.0, 0), ("arc", 0, 2)],
    fifo=8, control="queued", frame="worktable", speed_factor=0.7, link_scale=0.95,
    origin=None, damage=0.0, seed=0,
)

# Found by review (helper, 14:20): frames 5 and 6 (a G6 to the profile's IK of where the arm stood,
# planned 0 s long, and a PWM frame) were written while the arm already rested at the last target;
# 50 ms later the rest "proved" them done while the arm, its own IK elsewhere, was only starting
# to turn (7 claimed, 5 finished).  A rest counts only from the arrival of the last frame written.
FRAMES_WRITTEN_DURING_THE_REST = dict(
    ops=[("joint", 4, 90.0, 6), ("arc", 5, 3), ("joint", 5, 90.0, 0), ("pwm", 1000.0), ("joint", 5, 30.0, 1),
         ("pwm", 2000.0)],
    fifo=8, control="queued", frame="worktable", speed_factor=2.0, link_scale=1.05,
    origin=None, damage=0.0, seed=898, speed_tolerance=1.05,
)

# Found by a sweep biased to such arms (the review's sweep_b.py, seed 4242): a joint move from a
# Cartesian end runs from where the arm's own IK put it, and on the way a joint half passed along
# the next joint frame's planned path — taken for the arm on that frame (3 claimed, 2 finished;
# 6 and 5 in the other).  A sighting now counts on such a move, never past it.
JOINT_PATH_ALONG_A_LATER_FRAME = dict(
    ops=[("pwm", 2000.0), ("pwm", 1000.0), ("line", 4, 6000.0), ("joint", 3, 90.0, 3), ("pose", 3),
         ("joint", 1, 30.0, 2), ("joint", 0, 90.0, 6), ("pwm", 1000.0)],
    fifo=50, control="queued", frame="robot", speed_factor=2.0, link_scale=0.95,
    origin=(10.0, -20.0, 5.0), damage=0.0, seed=293, speed_tolerance=1.05,
)
JOINT_PATH_ALONG_A_LATER_FRAME_2 = dict(
    ops=[("pwm", 2000.0), ("joint", 4, 90.0, 3), ("pose", 1), ("line", 4, 6000.0), ("delay", 50.0),
         ("joint", 3, 30.0, 6), ("joint", 5, 90.0, 1), ("delay", 50.0)],
    fifo=50, control="arrival", frame="worktable", speed_factor=2.0, link_scale=1.05,
    origin=(10.0, -20.0, 5.0), damage=0.1, seed=519, speed_tolerance=1.05,
)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("case", [OVERSTATED, HELD_BY_THE_FIFO_BOUND, HELD_BY_A_REST_FAR_FROM_THE_TARGET,
                                  HELD_BY_A_REST_AT_THE_TARGET, HELD_BY_A_REST_AT_THE_TARGET_AFTER_A_TURN,
                                  JOINT_MOVE_FROM_A_CARTESIAN_END, ARC_PLANNED_AS_A_LINE, FRAMES_WRITTEN_DURING_THE_REST,
                                  JOINT_PATH_ALONG_A_LATER_FRAME, JOINT_PATH_ALONG_A_LATER_FRAME_2],
                         ids=["overstated", "held-by-the-fifo-bound", "held-by-a-rest-far-from-the-target",
                              "held-by-a-rest-at-the-target", "held-by-a-rest-at-the-target-after-a-turn",
                              "joint-move-from-a-cartesian-end", "arc-planned-as-a-line",
                              "frames-written-during-the-rest", "joint-path-along-a-later-frame",
                              "joint-path-along-a-later-frame-2"])
def test_a_move_from_where_only_unverified_kinematics_put_the_arm_is_never_overstated_nor_held_for_ever(case):
    check_random_job(**case)



@pytest.mark.timeout(60)
@pytest.mark.parametrize("fifo, extra", [(50, 0), (12, 10)], ids=["end-of-job", "held-mid-job"])
def test_a_g54_inside_a_rest_that_makes_the_arm_read_as_the_last_target_keeps_the_rest_from_proving_it(fifo, extra):
    """Found by review: after an arc from an unverified joint end (the bound stuck behind it), two
    delays at the arc's end A with a G54 between them that makes the worktable X/Y/Z read there as
    the last target T; then a G54 back and the way to T.  The arm resting in the second delay read
    as T — the run's first frame alone said it rests far from T — and the rest proved all 9 frames
    while 5 had run (held mid-job, with 10 M codes more: 2 frames dropped).  Every pose a run holds
    counts now."""
    a, t = POINTS[1], POINTS[5]
    b = (t[0] + 5.0, t[1], t[2])

    def line(p):
        return LinearMove(*p, 180.0, 0.0, 0.0, 1500.0, 3000.0)

    commands = [JointMove(*_joints(POINTS[0]), 1500.0, 30.0, smoothing=0),
                ArcStart(*POINTS[2], 180.0, 0.0, 0.0, 1500.0, 50.0, 4000.0), ArcEnd(*a, 180.0, 0.0, 0.0, 1500.0, 4000.0),
                Delay(3000.0), SetWorktableOrigin(*(p - q for p, q in zip(a, t))), Delay(3000.0),
                SetWorktableOrigin(0.0, 0.0, 0.0), line(b), line(t)] + [MCode(7)] * extra + ([line(b)] if extra else [])
    check_job(commands, fifo, "queued", "worktable", 2.0, 1.0, profile_speed_factor=1.0)


@pytest.mark.timeout(60)
def test_a_joint_move_from_a_cartesian_end_the_arm_reaches_outside_the_profiles_joint_limits():
    """Found by review: the joint move's time allowance took the profile's joint limits as where
    the arm's own IK may put it; with links 5 % long the arm (as the simulator's IK does when no
    solution lies within the limits) stood 124 degrees past J5's limit, a 325-degree turn against an
    allowance of 229 (5 claimed, 1 finished).  The allowance is at least a whole turn now."""
    joints = {"j1_deg": [-170.0, 170.0], "j2_deg": [-90.0, 100.0], "j3_deg": [-120.0, 120.0],
              "j4_deg": [-180.0, 180.0], "j5_deg": [-120.0, 120.0], "j6_deg": [-180.0, 180.0]}
    kinematics = parse_profile({"joints": joints}).kinematics
    p = (-320.0, 0.0, 60.0)
    q = kinematics.joints_of(p + (180.0, 0.0, 0.0), kinematics.home)
    commands = [LinearMove(*p, 180.0, 0.0, 0.0, 1500.0, 3000.0), JointMove(*q, 1500.0, 30.0, smoothing=0),
                MCode(7), MCode(7), MCode(7), LinearMove(-300.0, 0.0, 100.0, 180.0, 0.0, 0.0, 1500.0, 3000.0)]
    check_job(commands, 50, "queued", "worktable", 1.0, 1.05, speed_tolerance=1.05, sections={"joints": joints})


HELD_JOB = """\
G1 X250 Y0 Z200 A180 B0 C0 S1000 F3000
G1 S2000
G6 J1=20 J2=10 J3=0 J4=0 J5=80 J6=0 F30
G300 X250 Y0 Z120 A180 B0 C0 R137.85 F900
G301 X200 Y-120 Z120 F900
G1 S1000
G1 S2000
G1 C45
"""


@pytest.mark.timeout(60)
def test_armctl_run_goes_on_past_the_fifo_bound_when_the_arm_rests_at_the_last_target(tmp_path):
    """The installed command, in a fresh process, in virtual time: a FIFO of 8 holds the arc
    from the joint move's end and the PWM frames behind it, which time cannot confirm.  The
    virtual host must be woken when the arm's rest may prove them (``Job.receive_status``'s
    news while the bound holds the job), or it reads on for ever."""
    (tmp_path / "held.txt").write_text(HELD_JOB)
    (tmp_path / "armctl.toml").write_text("[connector]\nfifo_frames = 8\n")
    result = subprocess.run(
        [sys.executable, "-m", "armctl", "run", "held.txt", "--json",
         "--port", "sim://?clock=virtual&fifo_frames=8&link_scale=1.05"],
        cwd=tmp_path, capture_output=True, text=True, timeout=30)
    summary = json.loads(result.stdout.splitlines()[-1])
    assert (result.returncode, summary["outcome"], summary["frames_sent"]) == (0, "finished", 8), result.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize("link_scale", ["0.8", "0.9", "1.0", "1.1"])
def test_a_move_from_an_unverified_joint_end_shorter_than_planned_is_no_sign_of_loss(tmp_path, link_scale):
    """A probed profile (``speed_tolerance = 1.05``: the loss checks' fastest arm is 1.05x the model)
    on an arm whose links differ: the line after the joint move starts elsewhere and was up to 10 %
    shorter — "frames may have been lost" (exit 1) at link_scale 0.9 before such a move counted as
    none of the least motion the loss checks require (``SentFrame.sure_before_s``)."""
    (tmp_path / "job.txt").write_text("G6 J1=30 J2=20 J3=10 J4=0 J5=60 J6=0 S1000 F90\n"
                                      "G1 X250 Y0 Z150 A180 B0 C0 F300\n")
    (tmp_path / "armctl.toml").write_text("[connector]\nspeed_tolerance = 1.05\n")
    result = subprocess.run(
        [sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", f"sim://?clock=virtual&link_scale={link_scale}"],
        cwd=tmp_path, capture_output=True, text=True, timeout=30)
    summary = json.loads(result.stdout.splitlines()[-1])
    assert (result.returncode, summary["outcome"]) == (0, "finished"), summary["messages"]


FAR_REST_JOB = """\
G6 J1=20 J2=10 J3=0 J4=0 J5=80 J6=0 S1500 F90
G300 X250 Y0 Z120 A180 B0 C0 R137.85 F4000
G301 X200 Y-120 Z120 F4000
G1 S1000 F3000
G222 X180 Y80 Z90 K1500 F5000
POSE 2
"""


@pytest.mark.timeout(60)
@pytest.mark.parametrize("link_scale", ["1.0", "1.05"])
def test_armctl_run_goes_on_when_held_after_the_arc_at_rest_far_from_the_pwm_frame(tmp_path, link_scale):
    """The installed command on HELD_BY_A_REST_FAR_FROM_THE_TARGET's shape (an arm 2x slower,
    control frames on arrival, the probe's speed_tolerance): held after the arc, the PWM frame at
    the arc's end, 100 mm from the last target, must not keep the arm's rest at that target from
    proving the frames written finished — before, the job waited for ever (here: the timeout)."""
    (tmp_path / "far.txt").write_text(FAR_REST_JOB)
    (tmp_path / "armctl.toml").write_text('[connector]\ncontrol_frames = "arrival"\nspeed_factor = 2.0\n'
                                          'speed_tolerance = 1.05\n')
    result = subprocess.run(
        [sys.executable, "-m", "armctl", "run", "far.txt", "--json",
         "--port", f"sim://?clock=virtual&control_frames=arrival&speed_factor=2&link_scale={link_scale}"],
        cwd=tmp_path, capture_output=True, text=True, timeout=30)
    summary = json.loads(result.stdout.splitlines()[-1])
    assert (result.returncode, summary["outcome"], summary["frames_sent"]) == (0, "finished", 6), result.stderr
