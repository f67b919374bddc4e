"""The engine's view skips a refresh only where it would change nothing: ``next_action`` at the
time ``wrote`` refreshed it, with nothing taken or asked since (armctl/core/job.py ``_fresh_s``).
Checked by refreshing a copy at every such skip — over virtual runs of the example scripts on
the simulator, and over the engine's host loop with a pause, a resume and a stop."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.core.job import Job

from test_job import FakeArm, drive, make_job

SCRIPTS = Path(__file__).resolve().parent.parent / "scripts"
# the fields ``Job._refresh`` sets
FOLLOWED = ("now_s", "queued_frames_bound", "queued_s", "last_done", "first_not_done", "pause_state", "pause_label",
            "feed_percent", "feed_clamped", "frames_by_reports", "frames_by_time", "frames_unseen")


@pytest.fixture
def skips(monkeypatch) -> list:
    """Every skipped refresh, checked against a refresh of a copy of the view at that moment."""
    seen: list = []
    next_action = Job.next_action

    def checked(self, now):
        if self._fresh_s == now:
            shown, version = self.view, self._control_version
            self.view = copy.copy(shown)
            self._refresh(now)  # on a copy of the view
            refreshed, self.view, self._control_version = self.view, shown, version
            assert [getattr(refreshed, f) for f in FOLLOWED] == [getattr(shown, f) for f in FOLLOWED]
            seen.append(now)
        return next_action(self, now)

    monkeypatch.setattr(Job, "next_action", checked)
    return seen


@pytest.mark.timeout(120)
@pytest.mark.parametrize("script", ["draw_square_circle.txt", "palletise.txt", "joint_routine.txt"])
def test_a_skipped_refresh_leaves_the_view_as_a_refresh_would(skips, script, monkeypatch):
    monkeypatch.chdir(SCRIPTS.parent)
    result = CliRunner().invoke(main, ["run", f"scripts/{script}", "--no-live", "--port", "sim://?clock=virtual"],
                                env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert len(skips) > 10  # the skip happened, after every frame written


@pytest.mark.timeout(30)
def test_a_pause_resume_or_stop_asked_after_a_write_is_refreshed(skips):
    job = make_job()
    arm = FakeArm(job)
    real_wrote = arm.wrote
    asked: list = []

    def wrote(action, now):  # the user's keys land between a write and the next question
        real_wrote(action, now)
        if action.statement is not None and not asked:
            asked.append(job.pause())
        elif action.control and len(asked) == 1:
            asked.append(job.resume())
        elif action.statement is not None and len(asked) == 2:
            asked.append(job.set_feed_override(50))

    arm.wrote = wrote
    finished, _ = drive(job, arm, stop_at_s=40.0)
    assert asked[:2] == [True, True]
    assert finished.outcome is not None
