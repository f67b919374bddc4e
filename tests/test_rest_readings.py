"""The job engine's "at rest" rule reads only what the arm reported: a kind whose reports were
lost (or corrupted) since the readings last changed says nothing about that time, so the arm is
at rest only when every kind was re-read, unchanged, ``REST_CHECK_S`` after the last change.

Found by Hypothesis (tests/test_streamer_sim.py): a wrist turning in place changes only joints
4-6; with their reports lost for 0.9 s, position, joints 1-3 and PWM stood still, the estimate
was over (the arm 1.3x slower than the model), and "at rest at the last target" confirmed a
frame the arm was still running."""

import copy

from armctl.core.armstate import ArmState
from armctl.core.job import REST_CHECK_S, Done, Job, Outcome, RunView, Write
from armctl.host.jobflow import wait_for_rest
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import JointsHighStatus, JointsLowStatus, PauseStatus, PositionStatus
from armctl.script import InitialState, compile_text
from armctl.core.streamer import Streamer

MODEL = MotionModel(load_profile())
START = MODEL.initial_pose()


def turn_wrist_job() -> Job:
    """One frame that turns the wrist in place (W 0 → 90): only joints 4-6 show it."""
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    x, y, z = START.xyz
    statements = list(compile_text(f"G1 X{x:.1f} Y{y:.1f} Z{z:.1f} A180 B0 C90 F3000\n", initial=initial))
    streamer = Streamer(MODEL, START)
    view = RunView(total_frames=len(statements), estimated_job_s=2.0, lead_s=streamer.lead_s,
                   capacity=streamer.limit_frames)
    job = Job(streamer, statements, view)
    assert isinstance(job.next_action(0.0), Write)
    job.wrote(0.0)
    return job


def report(job: Job, now: float, joints_high=None) -> None:
    """A rotation of status frames at ``now``; joints 4-6 only when given (else lost)."""
    x, y, z = (round(v, 1) for v in START.xyz)
    frames = [PositionStatus(x, y, z), JointsLowStatus(*(round(v, 2) for v in START.joints[:3])), PauseStatus(0, 1500)]
    if joints_high is not None:
        frames.append(JointsHighStatus(*joints_high))
    for frame in frames:
        job.receive_status(frame, now)


def test_a_kind_not_reported_since_the_last_change_is_no_rest():
    job = turn_wrist_job()
    sent = job.streamer.pending[0]
    turn_s = sent.segment.duration_s
    before = tuple(round(v, 2) for v in sent.segment.start.joints[3:])
    after = tuple(round(v, 2) for v in sent.segment.end.joints[3:])
    assert before != after and turn_s > 0.5  # the frame moves joints 4-6 only, for a while
    report(job, 0.1, joints_high=before)  # every kind read once, before the turn shows
    now = 0.1
    # The arm turns for 1.5 × the model's time; joints 4-6 reports are all lost meanwhile.  The
    # other kinds stand still well past the estimate and REST_CHECK_S: that is not rest.
    while now < 1.5 * turn_s:
        now += 0.03
        report(job, now)
        assert not job.arrival.arm_at_rest(now)
        assert not isinstance(job.next_action(now), Done)
    assert job.streamer.consumed_lower_bound == 0
    # Joints 4-6 read again, at the end of the turn: the readings changed there; once every kind
    # was re-read REST_CHECK_S later, unchanged, the arm is at rest at its last target.
    report(job, now + 0.03, joints_high=after)
    changed_s = now = now + 0.03
    while now < changed_s + REST_CHECK_S:
        now += 0.03
        report(job, now, joints_high=after if now >= changed_s + REST_CHECK_S else None)
        assert now >= changed_s + REST_CHECK_S or not job.arrival.arm_at_rest(now)
    assert job.arrival.arm_at_rest(now)
    assert job.next_action(now) == Done(Outcome.FINISHED)
    assert job.streamer.all_consumed


def test_past_the_deadline_a_still_arm_is_waited_for_until_every_kind_is_read_again():
    # An arm almost as slow as the time bound allows ends its turn near the deadline; its joints
    # 1-3 reports are then lost past it.  Still, but not proven at rest: the engine waits (a slack
    # after the last change) for the next reports rather than ending "no confirmation".
    job = turn_wrist_job()
    segment = job.streamer.pending[0].segment
    before = tuple(round(v, 2) for v in segment.start.joints[3:])
    after = tuple(round(v, 2) for v in segment.end.joints[3:])
    report(job, 0.1, joints_high=before)
    assert not isinstance(job.next_action(0.1), Done)
    deadline_s = job.end.deadline_s
    changed_s = 1.9 * segment.duration_s  # the turn ends; every kind read then
    report(job, changed_s, joints_high=after)
    assert changed_s + REST_CHECK_S < deadline_s  # at rest before the deadline, if the reports came
    now = changed_s
    x, y, z = (round(v, 1) for v in START.xyz)
    while now < deadline_s + 0.1:
        now += 0.03
        for frame in (PositionStatus(x, y, z), JointsHighStatus(*after), PauseStatus(0, 1500)):  # joints 1-3 lost
            job.receive_status(frame, now)
        assert not isinstance(job.next_action(now), Done)
    now += 0.03
    report(job, now, joints_high=after)
    assert job.next_action(now) == Done(Outcome.FINISHED)


class ScriptedLink:
    """Enough of a Link for ``wait_for_rest``: a clock that moves 50 ms per wait, and an
    ArmState fed by ``frames(now)`` (the status frames read by then)."""

    def __init__(self, frames) -> None:
        self.now, self.frames, self.state = 0.0, frames, ArmState()

    def clock(self) -> float:
        return self.now

    def snapshot(self):
        return copy.deepcopy(self.state), 0, 0, 0

    def wait_until(self, predicate, timeout_s: float) -> bool:
        self.now += timeout_s
        for frame in self.frames(self.now):
            self.state.update(frame, self.now)
        return False


def test_waiting_for_rest_before_a_resume_needs_every_kind_read_again():
    # The wrist turns until 2 s; its joints 4-6 reports are lost from 0.5 s to 2.5 s.  The
    # position and joints 1-3 stand still all along: the arm is at rest only once joints 4-6
    # are read again (at the end of the turn), and REST_CHECK_S later, unchanged.
    x, y, z = (round(v, 1) for v in START.xyz)
    low = tuple(round(v, 2) for v in START.joints[:3])

    def frames(now: float):
        high = (0.0, 90.0, round(min(now, 2.0) * 45.0, 2))
        yield PositionStatus(x, y, z)
        yield JointsLowStatus(*low)
        if not 0.5 <= now < 2.5:
            yield JointsHighStatus(*high)

    link = ScriptedLink(frames)
    state = wait_for_rest(link, timeout_s=10.0)
    assert state.joints_deg[5] == 90.0  # the end of the turn, not the stale reading from 0.45 s
    assert link.now >= 2.5 + REST_CHECK_S


def test_at_rest_in_a_delay_before_a_wrist_turn_is_not_the_end():
    # A delay, then a short wrist turn in place: the arm rests in the delay at the X/Y/Z of the
    # last target, every kind read afresh (one kind every 30 ms).  On an arm slower than the
    # model the estimate, re-anchored on each position report, runs out within a rotation
    # (Hypothesis: a PWM-only move, a delay, then a turn, 1.6x); the delay is done only once the
    # streamer's lower bound passes it (its time bound here), and the end waits for the turn.
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    x, y, z = START.xyz
    statements = list(compile_text(f"G4 P3000\nG1 X{x:.1f} Y{y:.1f} Z{z:.1f} A180 B0 C5 F3000\n", initial=initial))
    streamer = Streamer(MODEL, START)
    job = Job(streamer, statements, RunView(total_frames=2, estimated_job_s=3.0, lead_s=streamer.lead_s,
                                            capacity=streamer.limit_frames))
    now = 0.0
    while len(streamer.pending) < 2:
        assert isinstance(job.next_action(now), Write)
        job.wrote(now)
        now += 0.06
    delay, turn = streamer.pending
    before = tuple(round(v, 2) for v in turn.segment.start.joints[3:])
    after = tuple(round(v, 2) for v in turn.segment.end.joints[3:])
    assert before != after and turn.segment.duration_s < 0.1  # shorter than a round of reports
    delay_ends_s = 2.0 * delay.segment.duration_s  # the arm twice slower than the model
    turn_ends_s = delay_ends_s + 2.0 * turn.segment.duration_s
    xyz = tuple(round(v, 1) for v in START.xyz)
    low = tuple(round(v, 2) for v in START.joints[:3])
    finished_at, step = None, 0
    while finished_at is None and now < turn_ends_s + 5.0:
        now, step = now + 0.03, step + 1
        share = min(max((now - delay_ends_s) / (turn_ends_s - delay_ends_s), 0.0), 1.0)
        high = tuple(round(a + (b - a) * share, 2) for a, b in zip(before, after))
        job.receive_status((PositionStatus(*xyz), JointsLowStatus(*low), JointsHighStatus(*high),
                            PauseStatus(0, 1500))[step % 4], now)
        if isinstance(job.next_action(now), Done):
            finished_at = now
    assert finished_at is not None and finished_at >= turn_ends_s + REST_CHECK_S
    assert job.outcome == Outcome.FINISHED and streamer.all_consumed


def written_job(text: str) -> Job:
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    statements = list(compile_text(text, initial=initial))
    streamer = Streamer(MODEL, START)
    job = Job(streamer, statements, RunView(total_frames=len(statements), estimated_job_s=3.0, lead_s=streamer.lead_s,
                                            capacity=streamer.limit_frames))
    now = 0.0
    while streamer.sent < len(statements):
        assert isinstance(job.next_action(now), Write)
        job.wrote(now)
        now += 0.06
    return job


def test_only_runs_long_enough_to_look_at_rest_wait_for_their_time_bound():
    x, y, z = START.xyz
    turn = f"G1 X{x:.1f} Y{y:.1f} Z{z:.1f} A180 B0 C45 F3000\n"
    # a G54 (no motion time) cannot hold even a slow arm still for REST_CHECK_S: rest decides
    assert written_job("G54 X0 Y0 Z0\n" + turn).end.resting_before_last_move() == []
    # 0.3 s of delays can, on an arm twice slower (0.6 s, with its per-frame slack): the time bound decides
    job = written_job("G4 P150\nG4 P150\n" + turn)
    assert [sent.index for sent in job.end.resting_before_last_move()] == [0, 1]
    # frames after the last motion are the trailing rule's, not these
    assert written_job(turn + "G4 P3000\n").end.resting_before_last_move() == []
