"""Pause, resume and feed override through the job engine (armctl/core/job.py), in virtual time.

Strategy: the engine drives the pure simulated arm (armctl/sim/model.py) directly — bytes
written go to ``SimulatedArm.write``, its status bytes come back through a ``StatusReader`` —
with time advanced by hand to the next status burst or the engine's own time.  No port, no
thread.  Both control-frame modes (H5: toggles queued in the FIFO, or acting on arrival) are
checked against the arm's own record: no frame of the job is taken while it is paused, the
job still ends ``finished`` with every frame run once, and the frames written after an
override carry the scaled speed.
"""

from __future__ import annotations

import pytest

from armctl.core.job import Done, Job, Outcome, RunView, Write
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import LinearMove, PauseToggle, StatusReader, decode_command
from armctl.script import InitialState, compile_text
from armctl.sim.model import SimOptions, SimulatedArm
from armctl.core.streamer import Streamer

PROFILE = load_profile()
MODEL = MotionModel(PROFILE)
START = MODEL.initial_pose()
X, Y, Z = START.xyz
JOB = "".join(f"G1 X{X + 20 * (k % 2):.1f} Y{Y + 2 * k:.1f} F1200\n" for k in range(1, 13))  # 12 moves, ~1 s each


def make(control_frames: str):
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    statements = list(compile_text(JOB, initial=initial))
    streamer = Streamer(MODEL, START)
    view = RunView(total_frames=len(statements), estimated_job_s=15.0, lead_s=streamer.lead_s, capacity=streamer.limit_frames)
    job = Job(streamer, statements, view, control_frames=control_frames)
    arm = SimulatedArm(SimOptions(profile=PROFILE, control_frames=control_frames))
    return job, arm, statements


def drive(job, arm, at=(), limit_s=200.0):
    """Run to the end; ``at``: (time, call(job, now)) done once each when time passes it.
    Returns (outcome, [(t, Write)], [(t, paused reported)])."""
    reader, now, writes, pauses = StatusReader(), 0.0, [], []
    pending = sorted(at, key=lambda item: item[0])
    while now < limit_s:
        for frame in reader.feed(arm.advance(now)):
            job.receive_status(frame, now)
            if frame.KIND == 4:
                pauses.append((now, frame.paused))
        while pending and pending[0][0] <= now:
            pending.pop(0)[1](job, now)
        action = job.next_action(now)
        if type(action) is Write:
            arm.write(action.frame, now)
            job.wrote(now)
            writes.append((now, action))
            continue
        if type(action) is Done:
            return action.outcome, writes, pauses
        times = [arm.next_output_time()]
        if action.until_s is not None:
            times.append(action.until_s)
        if pending:
            times.append(pending[0][0])
        now = max(now + 1e-6, min(times))
    raise AssertionError("the job did not end")


def _taken(arm):
    """(start, command) of every frame the arm took, in order."""
    return [(e.start_s, e.command) for e in arm.execution_log]


@pytest.mark.parametrize("control_frames", ["queued", "arrival"])
def test_pause_holds_the_feed_and_the_arm_and_resume_finishes_the_job(control_frames):
    job, arm, statements = make(control_frames)
    seen = {}

    def pause(job, now):
        assert job.pause() and job.view.pause_state == "running"  # the view follows at the next action
        seen["asked"] = now

    def resume(job, now):
        assert job.view.pause_state == "paused" and job.view.pause_label == "paused"  # the arm said so
        assert job.resume()

    outcome, writes, pauses = drive(job, arm, at=[(3.0, pause), (12.0, resume)])
    assert outcome is Outcome.FINISHED
    toggles = [(t, w) for t, w in writes if w.control is not None]
    assert [w.frame for _, w in toggles] == [PauseToggle().encode()] * 2
    paused_at = min(t for t, p in pauses if p)
    resumed_at = max(t for t, p in pauses if p)
    # nothing of the job written between the pause asked and the resume toggle
    assert not [t for t, w in writes if w.statement is not None and seen["asked"] <= t < toggles[1][0]]
    # the arm took no job frame while it reported paused
    moves = [t for t, command in _taken(arm) if isinstance(command, LinearMove)]
    assert not [t for t in moves if paused_at < t < resumed_at]
    if control_frames == "arrival":
        assert paused_at - seen["asked"] < 0.7  # at once: the next pause reports say so
    # every frame of the job ran once, in order
    assert [c for _, c in _taken(arm) if isinstance(c, LinearMove)] == [s.command for s in statements]
    assert arm.frames_dropped == 0


def test_the_override_scales_the_frames_written_after_it():
    job, arm, statements = make("queued")
    outcome, writes, _ = drive(job, arm, at=[(2.0, lambda job, now: job.set_feed_override(150))])
    assert outcome is Outcome.FINISHED
    sent = [(t, decode_command(w.frame)) for t, w in writes if w.statement is not None]
    before = [c.speed_mm_min for t, c in sent if t < 2.0]
    after = [c.speed_mm_min for t, c in sent if t >= 2.0]
    assert before and after
    assert set(before) == {1200.0} and set(after) == {1800.0}
    assert job.view.feed_percent == 150


def test_stop_while_pausing_sends_no_second_toggle():
    job, arm, _ = make("queued")
    outcome, writes, _ = drive(job, arm, at=[(3.0, lambda job, now: job.pause()),
                                              (3.2, lambda job, now: job.request_stop())])
    assert outcome is Outcome.INTERRUPTED
    assert sum(1 for _, w in writes if w.frame == PauseToggle().encode()) == 1
    assert any("already on its way" in m for m in job.view.messages)


class _FullFifo:
    """A pacing strategy that counts the FIFO as full: no frame of the job may go."""

    def next_write_time(self, now, command=None):
        return None

    def receive_status(self, frame, now):
        pass

    def wrote(self, command, now, tag=None):
        pass


def test_a_toggle_is_not_held_behind_a_fifo_counted_full():
    job, _, _ = make("arrival")
    job.pacing = _FullFifo()
    assert type(job.next_action(0.0)) is not Write  # the job's frames wait
    assert job.pause()
    action = job.next_action(0.01)
    assert type(action) is Write and action.frame == PauseToggle().encode() and action.control
    job.wrote(0.01)
    assert type(job.next_action(0.02)) is not Write  # the feed is held, and the FIFO still full
    assert job.resume()
    action = job.next_action(0.2)  # once the wire is free again
    assert type(action) is Write and action.frame == PauseToggle().encode()
