"""A job started while the arm still moves: frames queued before it (another program on the
line, or an armctl killed mid-job) keep the arm at work after the job's first reading.  The job
was planned from the latest report of a moving arm, and its first frames timed from when they
landed, though the arm ran them only after the queue before them: a reachable job ended
"finished, unproven" (exit 1), and pick_and_place blamed the arm's speed ("ran at least 4.54x
slower ... probe it"), a wrong diagnosis that sends the user to re-calibrate a sound arm.
``read_arm`` now waits for the arm to come to rest first — saying so — within the bound a resume
waits (``jobflow.rest_wait_s``), and sends nothing when it does not come to rest.  The
simulator's own record (``execution_log``) is the truth."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.script import compile_text
from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)

URL = "sim://?clock=virtual"
FIRST = "G90\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n"
PICK = (Path(__file__).resolve().parent.parent / "scripts" / "pick_and_place.txt").read_text()


def _leftover_script(feed_mm_min: float) -> str:
    """One move another host queued: 100 mm at ``feed_mm_min``, from where FIRST leaves the arm."""
    return f"G90\nG1 X250 Y-100 Z150 A180 B0 C0 S1000 F{feed_mm_min:g}\n"


def _leftover(feed_mm_min: float) -> list[bytes]:
    return [statement.command.encode() for statement in compile_text(_leftover_script(feed_mm_min))]


def _job_on_arm_left_moving(tmp_path, monkeypatch, url: str, queued: str, job: str, *options: str,
                            first_must_finish: bool = True):
    """FIRST run to its end on ``url``, then the frames of ``queued`` (a script another host sent)
    written to the arm, then ``armctl run job.txt OPTIONS`` (``job``): its result and the arm's port."""
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    (tmp_path / "first.txt").write_text(FIRST)
    first = CliRunner().invoke(main, ["run", "first.txt", "--port", url], env={"ARMCTL_PORT": None})
    if first_must_finish:
        assert first.exit_code == 0, first.output
    port = ports[url]
    port.is_open = True
    for statement in compile_text(queued):
        port.write(statement.command.encode())
    (tmp_path / "job.txt").write_text(job)
    return CliRunner().invoke(main, ["run", "job.txt", *options, "--port", url], env={"ARMCTL_PORT": None}), port


def _run_on_moving_arm(tmp_path, monkeypatch, script: str, feed_mm_min: float = 1200):
    """A leftover move at ``feed_mm_min`` before ``script`` (``_job_on_arm_left_moving``), run with
    ``--json``: the result, its summary (None when it printed none) and the simulated arm."""
    result, port = _job_on_arm_left_moving(tmp_path, monkeypatch, URL, _leftover_script(feed_mm_min), script, "--json")
    last = (result.stdout.splitlines() or [""])[-1]
    return result, json.loads(last) if last.startswith("{") else None, port.model


def test_a_job_on_a_moving_arm_waits_for_rest_and_ends_finished(tmp_path, monkeypatch):
    result, summary, model = _run_on_moving_arm(
        tmp_path, monkeypatch, "G90\nG1 X360 Y0 Z150 A180 B0 C0 S1000 F3000\nG6 J1=-7.6 J2=11.4 J3=-7.9 J4=0 J5=90 J6=0 F30\n")
    assert (result.exit_code, summary["outcome"]) == (0, "finished"), summary
    assert "waiting for it to come to rest" in result.stderr, result.stderr
    leftover = model.execution_log[1]
    assert leftover.outcome == "done"
    assert model.frames_received[2].arrival_s >= leftover.end_s  # the job's first frame: written once the arm rested


def test_pick_and_place_on_a_moving_arm_does_not_blame_the_arm_s_speed(tmp_path, monkeypatch):
    result, summary, model = _run_on_moving_arm(tmp_path, monkeypatch, PICK)
    assert (result.exit_code, summary["outcome"]) == (0, "finished"), summary
    assert not any("slower" in message for message in summary["messages"]), summary["messages"]
    assert model.frames_dropped == 0


def test_an_arm_that_does_not_come_to_rest_gets_nothing(tmp_path, monkeypatch):
    """A leftover of 100 mm at F10 (600 s): longer than the wait; the job sends nothing, exit 1."""
    result, summary, model = _run_on_moving_arm(tmp_path, monkeypatch, PICK, feed_mm_min=10)
    assert result.exit_code == 1, result.output
    assert "did not come to rest" in result.stderr and "nothing was sent" in result.stderr, result.stderr
    assert len(model.execution_log) == 2, model.execution_log  # FIRST's frame and the leftover: no frame of the job


@pytest.mark.realtime
def test_a_job_on_an_arm_another_process_left_moving_installed(tmp_path):
    """The installed command in a fresh process on ``armctl sim --pty`` (its own process, 10x
    time): a move written to the arm just before (20 s of the arm's time, 2 s of the wall's);
    ``armctl run`` says it waits, and the job's first frame lands after that move ended."""
    from journal_crash import pty_arm

    stats = tmp_path / "stats.json"
    (tmp_path / "job.txt").write_text("G90\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n")
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")  # no probe record of another test's arm
    with pty_arm("--url", "sim://?speed=10", "--stats", str(stats), env=env) as pty:
        with open(pty, "wb", buffering=0) as line:
            line.write(b"".join(_leftover(300)))
        time.sleep(0.5)  # the frame has landed and the arm moves when armctl first reads it
        done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", pty],
                              cwd=tmp_path, capture_output=True, text=True, timeout=40, env=env)
    assert "waiting for it to come to rest" in done.stderr, done.stderr
    assert json.loads(done.stdout.splitlines()[-1])["frames_sent"] == 1, done.stdout
    seen = json.loads(stats.read_text())
    (_, leftover_start_s, leftover_end_s, outcome), = seen["executions"][:1]
    assert outcome == "done" and seen["frames"][1][1] >= leftover_end_s, seen


def test_a_resume_says_it_waits_for_an_arm_still_at_work(tmp_path, monkeypatch):
    """``--resume`` waits for the arm to run out what was queued (``resume_start``); it did so in
    silence, up to --timeout + 2 x --lead + 2 s with nothing on the screen.  Now it says why."""
    from test_resume_exactly_once import _stop_after

    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    (tmp_path / "job.txt").write_text(FIRST + "".join(f"G1 X{250 + 5 * k} Y{(k % 4) * 5}\n" for k in range(1, 20)))
    _stop_after(monkeypatch, 6)
    first = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--log", "job.log", "--abort", "none", "--port", URL],
                               env={"ARMCTL_PORT": None})
    assert first.exit_code == 130, first.output
    port = ports[URL]  # the same arm, still where the first run left it
    port.is_open = True
    for frame in _leftover(1200):  # another host's move meanwhile: the arm at work when the resume reads it
        port.write(frame)
    second = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--resume", "job.log", "--port", URL],
                                env={"ARMCTL_PORT": None})
    assert "--resume: the arm is still at work" in second.stderr, second.output
