"""The work ``armctl run`` does for each frame on the host (issue 23): a repeat block's passes are
compiled once or twice, not once a frame, in each pass over the script (armctl/script/repeats.py),
the estimate plans no LinearMove's segment (``Planner.feed_line``), and each frame's segment is
planned once, by the streamer's gate as the frame is written — the simulated arm plans its own."""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.core.motion import MotionModel, Planner
from armctl.script.execute import StatementExecution

pytestmark = pytest.mark.timeout(60)
PASSES = 300
JOB = ("G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\n"
       f"O<a> repeat [{PASSES}]\nG1 Y-49 F3000\nG1 Y-50\nO<a> endrepeat\n")
FRAMES = 1 + 2 * PASSES


def test_each_frame_is_planned_once_on_the_host_and_each_repeated_pass_compiled_once(tmp_path, monkeypatch):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    plans, feeds, lines = Counter(), [0], [0]
    plan, feed, execute, plain = MotionModel.plan, Planner.feed, StatementExecution._execute, StatementExecution._plain_move

    def counting_plan(self, *args, **kwargs):
        plans[Path(sys._getframe(1).f_code.co_filename).parent.name + "/" + sys._getframe(1).f_code.co_name] += 1
        return plan(self, *args, **kwargs)

    def counting_feed(self, command):
        feeds[0] += 1
        return feed(self, command)

    def counting_execute(self, *args):
        lines[0] += 1
        return execute(self, *args)

    def counting_plain(self, *args):
        lines[0] += 1
        return plain(self, *args)

    monkeypatch.setattr(MotionModel, "plan", counting_plan)
    monkeypatch.setattr(Planner, "feed", counting_feed)
    monkeypatch.setattr(StatementExecution, "_execute", counting_execute)
    monkeypatch.setattr(StatementExecution, "_plain_move", counting_plain)
    result = CliRunner().invoke(main, ["-q", "run", str(script), "--no-live", "--port", "sim://?clock=virtual"],
                                env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert f"frames: {FRAMES} of {FRAMES} sent" in result.output
    assert plans["streamer/plan"] == FRAMES  # the gate: once a frame
    assert plans["sim/_start_next"] == FRAMES  # the simulated arm's own
    assert feeds[0] == 0  # the estimate and lint time every LinearMove without its segment
    # lint, the estimate and the stream each run the body a few times, not PASSES times (26 lines in all)
    assert lines[0] <= 30, lines[0]
