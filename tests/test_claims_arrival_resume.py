"""Issue 21 item 4: after a stop on an arm whose control frames act as they land, the printed
resume runs every line once — nothing twice (beyond the one re-send of the frozen move, an
absolute move to where the arm then is) and nothing never.

- Unprobed (the profile says H5, control frames queue; the arm acts on arrival): the abort's
  pause froze the arm mid-move with frames still queued, no RESET CONNECTOR followed, and the
  resume's start-up toggle released them before its resume line sent them again — 24 frames ran
  twice on a 200-frame raster stopped after 60 (the issue: 40).  Now the engine sees the arm
  frozen mid-move (a queued pause acts only between frames), says so, and clears the queue with a
  RESET CONNECTOR (acting as it lands on such an arm).
- Probed (``control_frames = "arrival"``): the arm paused at the last target written with the
  frames after its last move (PWM changes, a delay) still queued; "at the last target" was taken
  for "every frame ran", the RESET CONNECTOR cleared them, and the resume started after them:
  lines 29-33 of scripts/joint_routine.txt never ran.  Now a pause that acted as it landed proves
  only the moves whose ends the arm reached.

Judged by the simulator's own record of executed frames (one arm kept across the two runs;
virtual time), and through the installed command in a fresh process (the API's ``stop``).
"""

from __future__ import annotations

import dataclasses
import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.core.protocol import AccelLinearMove, ArcEnd, Delay, GoToPose, JointMove, LinearMove
from armctl.sim.executor import DONE
from claims_common import fresh, raster
from test_resume_exactly_once import _open_one_arm, _stop_after

JOINT_ROUTINE = Path(__file__).resolve().parent.parent / "scripts" / "joint_routine.txt"
MOTION = (LinearMove, AccelLinearMove, JointMove, ArcEnd, GoToPose, Delay)


def _executed(arm) -> list[tuple]:
    return [(type(e.command).__name__, *(round(v, 1) if isinstance(v, float) else v
                                        for v in dataclasses.astuple(e.command)))
            for e in arm.execution_log if isinstance(e.command, MOTION) and e.outcome == DONE]


def _collapsed(executed: list) -> list:
    return [step for k, step in enumerate(executed) if k == 0 or executed[k - 1] != step]


def _stop_and_resume(tmp_path, monkeypatch, script: str, url: str, stop_after: int, toml: str = "") -> tuple:
    """The job run once whole on its own arm, then stopped after ``stop_after`` frames and resumed
    on another: (the whole run's executions, the stopped-and-resumed ones, the two outputs)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(script, encoding="utf-8")
    if toml:
        (tmp_path / "armctl.toml").write_text(toml, encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    whole = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url + "&seed=1"])
    assert whole.exit_code == 0, whole.output
    _stop_after(monkeypatch, stop_after)
    first = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url])
    assert first.exit_code == 130, first.output
    resume = re.search(r"^resume with: (.*)$", first.stdout, re.M)
    second = CliRunner().invoke(main, shlex.split(resume.group(1))[1:] + ["--no-live"])
    assert second.exit_code == 0, (first.output, second.output)
    return _executed(ports[url + "&seed=1"].model), _executed(ports[url].model), first, second


def test_unprobed_arrival_arm_frozen_mid_move_resumes_without_running_queued_frames_twice(tmp_path, monkeypatch):
    whole, stopped, first, _ = _stop_and_resume(tmp_path, monkeypatch, raster(200),
                                                "sim://?clock=virtual&control_frames=arrival", 60)
    assert "the arm paused mid-move with frames still queued" in first.stderr
    assert _collapsed(stopped) == whole  # every frame, in order
    assert len(stopped) - len(whole) <= 1  # the one frozen move, re-sent to where the arm is


@pytest.mark.parametrize("stop_after", [9, 15])
def test_probed_arrival_arm_paused_at_the_last_target_runs_the_frames_after_its_last_move(tmp_path, monkeypatch,
                                                                                        stop_after):
    whole, stopped, first, second = _stop_and_resume(tmp_path, monkeypatch, JOINT_ROUTINE.read_text(encoding="utf-8"),
                                                     "sim://?clock=virtual&control_frames=arrival", stop_after,
                                                     '[connector]\ncontrol_frames = "arrival"\n')
    assert _collapsed(stopped) == _collapsed(whole), (first.output, second.output)
    assert len(stopped) - len(whole) <= 1


def test_a_fresh_process_stopped_through_the_api_resumes_exactly_once(tmp_path):
    (tmp_path / "job.txt").write_text(raster(200), encoding="utf-8")
    program = (
        "import dataclasses\n"
        "from armctl import Arm\n"
        "url = 'sim://?clock=virtual&control_frames=arrival'\n"
        "with Arm.open(port=url) as arm:\n"
        "    def progress(p):\n"
        "        if p.frames_sent >= 60:\n"
        "            arm.stop()\n"
        "    first = arm.run('job.txt', on_progress=progress)\n"
        "    second = arm.run('job.txt', from_line=first.resume_line)\n"
        "    model = arm._link.port.model\n"
        "    done = [(e.command.x_mm, e.command.y_mm) for e in model.execution_log\n"
        "            if type(e.command).__name__ == 'LinearMove' and e.outcome == 'done']\n"
        "    print(first.outcome, second.outcome, len(done), len(set(done)), model.frames_dropped)\n"
        "    print(*first.messages, sep='\\n')\n")
    result = fresh(["-c", program], tmp_path)
    assert result.returncode == 0, result.stderr
    counts, *messages = result.stdout.splitlines()
    first, second, executed, distinct, dropped = counts.split()
    assert (first, second, distinct, dropped) == ("interrupted", "finished", "200", "0"), result.stdout
    assert int(executed) - 200 <= 1, result.stdout  # at most the frozen move, re-sent
    assert any("paused mid-move with frames still queued" in m for m in messages), result.stdout
