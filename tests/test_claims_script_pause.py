"""Issue 22: a script's own ``PAUSE`` never hangs a run.

The arm pauses where the script says; the frames after the PAUSE are not written while it is
paused (on an arm whose control frames queue, H5, a frame behind the PAUSE would sit at the head
of the paused FIFO, where the resume toggle could never reach the head), and the run ends as
soon as the arm reports the pause: stopped, "paused by the script", exit 1, with the printed
``--from-line`` resume after the PAUSE line.  That resume (its start-up sends the one toggle that
un-pauses the arm) runs every line once.  A PAUSE that ends the script leaves the arm paused as
the script asks: every line ran, ``done``.  Virtual time; through the installed command in a
fresh process, and the API.
"""

from __future__ import annotations

import json
import re
import shlex
import subprocess

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.core.protocol import GoToPose, LinearMove, PauseToggle
from armctl.sim.executor import DONE
from claims_common import fresh
from test_resume_exactly_once import _open_one_arm

SCRIPT = ("G1 X269.46 Y124.08 Z204.55 A180 B0 C0 S1500 F3000\n"
          "PAUSE\n"
          "POSE 3\n"
          "G1 X286.52 Y140.45 Z55.33 A180 B0 C0\n")


def _armctl(*args: str, cwd) -> subprocess.CompletedProcess:
    return fresh(["-m", "armctl", *args], cwd, timeout_s=40)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_a_scripts_pause_ends_the_run_paused_in_a_fresh_process(tmp_path, control):
    (tmp_path / "job.txt").write_text(SCRIPT, encoding="utf-8")
    (tmp_path / "armctl.toml").write_text(f'[connector]\ncontrol_frames = "{control}"\n', encoding="utf-8")
    url = f"sim://?clock=virtual&control_frames={control}"
    result = _armctl("run", "job.txt", "--no-live", "--port", url, cwd=tmp_path)
    assert result.returncode == 1, (result.stdout, result.stderr)
    assert "stopped: paused by the script" in result.stderr
    assert "paused by the script's PAUSE at line 2" in result.stderr
    assert "frames: 2 of 4 sent" in result.stdout  # nothing after the PAUSE
    assert "last line known executed: 2" in result.stdout
    assert re.search(r"^resume with: armctl run job.txt --from-line 3 ", result.stdout, re.M), result.stdout

    as_json = _armctl("run", "job.txt", "--json", "--port", url, cwd=tmp_path)
    summary = json.loads(as_json.stdout.splitlines()[-1])
    assert as_json.returncode == 1 and summary["outcome"] == "paused by the script", as_json.stdout
    assert summary["resume_line"] == 3 and summary["last_line_executed"] == 2


@pytest.mark.timeout(60)
def test_a_scripts_pause_through_the_api_ends_with_the_result(tmp_path):
    (tmp_path / "job.txt").write_text(SCRIPT, encoding="utf-8")
    program = ("from armctl import Arm, JobFailed\n"
               "with Arm.open(port='sim://?clock=virtual') as arm:\n"
               "    try:\n"
               "        arm.run('job.txt')\n"
               "    except JobFailed as error:\n"
               "        print(error.result.outcome, error.result.resume_line)\n")
    result = fresh(["-c", program], tmp_path, timeout_s=40)
    assert result.stdout.strip() == "paused by the script 3", (result.stdout, result.stderr)


@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_the_printed_resume_after_a_scripts_pause_runs_every_line_once(tmp_path, monkeypatch, control):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(SCRIPT, encoding="utf-8")
    (tmp_path / "armctl.toml").write_text(f'[connector]\ncontrol_frames = "{control}"\n', encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    url = f"sim://?clock=virtual&control_frames={control}"
    first = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url])
    assert first.exit_code == 1, first.output
    resume = re.search(r"^resume with: (.*)$", first.stdout, re.M)
    second = CliRunner().invoke(main, shlex.split(resume.group(1))[1:] + ["--no-live"])
    assert second.exit_code == 0, second.output
    arm = ports[url].model
    done = [type(e.command).__name__ for e in arm.execution_log
            if isinstance(e.command, (LinearMove, GoToPose, PauseToggle)) and e.outcome == DONE]
    # the script's PAUSE, then the resume's own toggle (it found the arm paused), each line once
    assert done == ["LinearMove", "PauseToggle", "PauseToggle", "GoToPose", "LinearMove"], done
    assert arm.frames_dropped == 0


def test_a_pause_that_ends_the_script_leaves_the_arm_paused_and_the_job_done(tmp_path):
    (tmp_path / "job.txt").write_text(SCRIPT.split("POSE")[0], encoding="utf-8")
    result = _armctl("run", "job.txt", "--no-live", "--port", "sim://?clock=virtual", cwd=tmp_path)
    assert result.returncode == 0, (result.stdout, result.stderr)
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert "the arm is paused, as the script's PAUSE at line 2 leaves it" in result.stderr


def test_a_pause_and_its_resume_in_the_script_run_through(tmp_path):
    script = SCRIPT.replace("PAUSE\n", "PAUSE\nPAUSE\n")
    (tmp_path / "job.txt").write_text(script, encoding="utf-8")
    result = _armctl("run", "job.txt", "--no-live", "--port", "sim://?clock=virtual", cwd=tmp_path)
    assert result.returncode == 0, (result.stdout, result.stderr)
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"


@pytest.mark.parametrize("control_frames", ["queued", "arrival"])
def test_a_user_pause_behind_the_scripts_pause_sends_no_toggle(control_frames):
    # the panel's or the API's pause, asked while the job waits behind its own PAUSE: a second
    # toggle would undo that pause (queued: resume the arm at the head of its FIFO)
    from armctl.core.job import Job, RunView
    from armctl.script import InitialState, compile_text
    from armctl.core.streamer import Streamer
    from test_job_pause import MODEL, START, X, Y, Z, drive, make

    _, arm, _ = make(control_frames)
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    script = f"G1 X{X + 20:.1f} Y{Y:.1f} Z{Z:.1f} F1200\nPAUSE\nG1 X{X:.1f} F1200\n"
    statements = list(compile_text(script, initial=initial))
    streamer = Streamer(MODEL, START)
    job = Job(streamer, statements, RunView(total_frames=3, estimated_job_s=3.0, lead_s=2.0, capacity=196),
              control_frames=control_frames)
    asked = []

    def pause(job, now):
        if len(job.written.script_toggles) == 1 and job.outcome is None:
            asked.append(job.pause())

    outcome, writes, _ = drive(job, arm, at=[(k / 10, pause) for k in range(1, 30)])
    assert asked and not any(asked)
    assert outcome == "paused by the script"
    assert [w.frame for _, w in writes].count(PauseToggle().encode()) == 1  # the script's own
