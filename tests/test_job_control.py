"""Pause, resume and feed override of a running job (armctl/core/job_control.py), pure.

Strategy: the state machine driven by hand — user requests in, the arm's (twice-agreeing)
pause state in, and what the engine is told out: a toggle due, the feed held, the command to
write, what the panel says, whether an abort sends its pause toggle.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from armctl.core.job_control import JobControl, PauseState
from armctl.host.profile import Speeds
from armctl.core.protocol import LinearMove

SPEEDS = Speeds(max_linear_mm_min=6000.0, max_joint_deg_s=120.0, max_accel_mm_s2=3200.0, attitude_deg_s=90.0)


def _statement(speed=1000.0):
    return SimpleNamespace(line=1, command=LinearMove(200.0, 0.0, 100.0, 180.0, 0.0, 0.0, 1500.0, speed))


def test_pause_then_resume_follows_the_arms_reports():
    control = JobControl(SPEEDS)
    control.observe(False)
    assert control.label == "running" and not control.holds_feed
    assert control.pause()
    assert control.holds_feed and control.label == "pausing…"
    assert control.take_toggle() and not control.take_toggle()  # one toggle, once
    control.observe(False)  # queued: the toggle waits behind the frames queued
    assert control.state is PauseState.PAUSING
    control.observe(None)  # two reports disagree: nothing is concluded
    control.observe(True)
    assert control.label == "paused" and control.holds_feed
    assert control.resume()
    assert control.label == "resuming…" and control.holds_feed  # until its toggle is written
    assert control.take_toggle()
    assert not control.holds_feed  # frames may follow the resume toggle
    control.observe(True)  # still paused until the toggle acts
    assert control.label == "resuming…"
    control.observe(False)
    assert control.state is PauseState.RUNNING


def test_resume_while_pausing_sends_the_second_toggle():
    control = JobControl(SPEEDS, "arrival")
    control.observe(False)
    control.pause()
    control.take_toggle()
    assert control.resume() and control.take_toggle()
    control.observe(False)
    assert control.state is PauseState.RUNNING


def test_no_toggle_to_an_arm_that_reports_it_is_paused():
    control = JobControl(SPEEDS)
    control.observe(True)  # paused by the job's own PAUSE line
    assert control.label == "paused (by the job)"
    assert not control.pause() and not control.toggle_due
    assert not control.abort_needs_toggle()


@pytest.mark.parametrize("steps, arm_paused, expected", [
    ([], False, True),  # running: the abort pauses the arm
    (["pause"], False, False),  # a pause is already on its way
    (["pause", "paused"], True, False),  # paused: a toggle would resume it
    (["pause", "paused", "resume"], True, True),  # the resume will act first: pause after it
])
def test_the_abort_sends_a_pause_toggle_only_when_the_arm_would_run_on(steps, arm_paused, expected):
    control = JobControl(SPEEDS)
    control.observe(False)
    for step in steps:
        if step == "paused":
            control.take_toggle()
            control.observe(True)
        else:
            getattr(control, step)()
    control.observe(arm_paused)
    assert control.abort_needs_toggle() is expected


def test_command_for_is_planned_once_and_follows_the_override():
    control = JobControl(SPEEDS)
    statement = _statement()
    first = control.command_for(statement)
    assert first is statement.command  # 100 %: the very command
    assert control.step_feed_override(+1) == 110
    scaled = control.command_for(statement)
    assert scaled.speed_mm_min == 1100.0 and control.command_for(statement) is scaled  # the same object twice
    assert control.set_feed_override(5) == 10 and control.set_feed_override(999) == 200


def test_an_unknown_control_mode_is_refused():
    with pytest.raises(ValueError):
        JobControl(SPEEDS, "sometimes")
