"""``armctl run --json`` and ``armctl run --log … / --resume LOG`` (issue 11, item 4).

Strategy: --json through CliRunner and through the installed command in a fresh process:
every stdout line must parse, the last is the one summary with the API's field names.  The
resume rules are checked on ``ResumePoint`` with hand-made records, the refusals (another
script, an edited one) through the CLI, and the whole promise end to end: a host killed with
SIGKILL mid-job against a simulated arm that outlives it (the pty bridge in this process,
wall clock), then ``--resume LOG`` against the same arm — the arm's own execution log must hold
every frame of the script exactly once, in order.
"""

from __future__ import annotations

import io

import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.host.api import RunResult
from armctl.ui.cli import main
from armctl.errors import ResumeRefused
from armctl.core.joblog import FrameEntry, NotProven, ResumePoint, read_resume_lines
from armctl.core.protocol import decode_command
from armctl.sim.bridge import serve_pty
from armctl.sim.model import SimOptions, SimulatedArm

SCRIPTS = Path(__file__).resolve().parent / "data" / "scripts_cli"
SHORT = SCRIPTS / "short_job.txt"
COMPILE_ERROR = SCRIPTS / "compile_error_job.txt"
FAST_SIM = "sim://?clock=virtual"
ARMCTL = [sys.executable, "-m", "armctl"]
# the summary is the Python API's result, field for field (the one place that builds both)
RESULT_FIELDS = {field.name for field in dataclasses.fields(RunResult)}
assert RESULT_FIELDS >= {"outcome", "frames_sent", "last_line_sent", "last_line_executed", "arm_time_s", "resume_line"}


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def _events(stdout: str) -> list[dict]:
    return [json.loads(line) for line in stdout.splitlines()]  # every line, or the test fails


def _check_stream(events: list[dict]) -> dict:
    assert [e["event"] for e in events].count("summary") == 1
    assert events[-1]["event"] == "summary"
    summary = events[-1]
    assert set(summary) - {"event", "diagnostics"} == RESULT_FIELDS
    return summary


# --- run --json --------------------------------------------------------------------------------


def test_json_lines_in_process():
    result = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--json"])
    assert result.exit_code == 0, result.output
    events = _events(result.stdout)
    summary = _check_stream(events)
    assert events[0]["event"] == "started" and events[0]["total_frames"] == 5
    assert summary["outcome"] == "finished" and summary["exit_code"] == 0
    assert (summary["frames_sent"], summary["total_frames"], summary["last_line_executed"]) == (5, 5, 6)
    assert summary["arm_time_s"] > 0 and summary["resume_line"] is None
    assert any(e["event"] == "progress" for e in events)
    assert "finished: the arm finished the job" in result.stderr  # for people: stderr


def test_json_summary_is_the_api_result_of_the_same_job():
    """One engine, one result: the same job on the same simulator gives the same object."""
    from armctl import Arm
    cli = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--json"])
    summary = _check_stream(_events(cli.stdout))
    del summary["event"]
    with Arm.open(port=FAST_SIM) as arm:
        result = arm.run(SHORT)
    assert result.to_json() == summary
    assert summary["arm_time_s"] > 0 and summary["exit_code"] == 0


def test_json_lines_from_the_installed_command():
    completed = subprocess.run([*ARMCTL, "run", str(SHORT), "--port", FAST_SIM, "--json"],
                               capture_output=True, text=True, timeout=60)
    assert completed.returncode == 0, completed.stderr
    summary = _check_stream(_events(completed.stdout))
    assert summary["outcome"] == "finished"
    assert "using the built-in simulator" in completed.stderr  # the banner is not on stdout


@pytest.mark.realtime
def test_json_ctrl_c_mid_job_ends_with_one_interrupted_summary():
    process = subprocess.Popen([*ARMCTL, "run", str(SCRIPTS / "timed_job.txt"), "--port", "sim://?speed=10", "--json"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        first = json.loads(process.stdout.readline())
        assert first["event"] == "started"
        time.sleep(0.3)
        process.send_signal(signal.SIGINT)
        rest, err = process.communicate(timeout=30)
    finally:
        process.kill()
    assert process.returncode == 130, err
    summary = _check_stream([first, *_events(rest)])
    assert summary["outcome"] == "interrupted" and summary["exit_code"] == 130
    assert summary["resume_line"] is not None and "--from-line" in summary["resume_command"]


def test_json_a_refused_script_is_one_summary_with_its_diagnostics():
    completed = subprocess.run([*ARMCTL, "run", str(COMPILE_ERROR), "--port", FAST_SIM, "--json"],
                               capture_output=True, text=True, timeout=60)
    assert completed.returncode == 1
    events = _events(completed.stdout)
    assert len(events) == 1
    summary = _check_stream(events)
    assert summary["outcome"] == "refused" and summary["exit_code"] == 1 and summary["frames_sent"] == 0
    assert summary["diagnostics"] and all(d["severity"] == "error" for d in summary["diagnostics"])
    assert "nothing was sent to the arm" in completed.stderr


def test_json_a_failure_before_the_first_frame_is_one_summary(tmp_path):
    other = tmp_path / "other.txt"
    other.write_text("G4 P10\n")
    log = tmp_path / "log.jsonl"
    log.write_text(json.dumps({"dir": "job", "script": "x", "sha256": "0" * 64, "from_line": 1}) + "\n")
    result = CliRunner().invoke(main, ["run", str(other), "--port", FAST_SIM, "--json", "--resume", str(log)])
    assert result.exit_code == 2
    summary = _check_stream(_events(result.stdout))
    assert summary["outcome"] == "failed" and summary["exit_code"] == 2


# --- the resume rules --------------------------------------------------------------------------

TARGET = {"kind": "line", "xyz_mm": [220.0, 10.0, 280.0], "joints_deg": [0.0] * 6}
ELSEWHERE = {"kind": "line", "xyz_mm": [200.0, 0.0, 250.0], "joints_deg": [0.0] * 6}


def _frames(last_target, next_line):
    """Frames of lines 1..7, the last one's target ``last_target``, then ``next_line``."""
    frames = [FrameEntry(n, n, n, n + 1, ELSEWHERE) for n in range(1, 7)]
    return (*frames, FrameEntry(7, 7, 7, next_line, last_target))


def test_at_the_last_target_every_frame_written_ran():
    point = ResumePoint(1, 2.0, _frames(TARGET, 8), confirmed=7, done=4)
    assert point.line_for((220.0, 10.1, 280.0), (None,) * 6) == 8
    finished = ResumePoint(1, 2.0, _frames(TARGET, None), confirmed=7, done=4)
    assert finished.line_for((220.0, 10.0, 280.0), (None,) * 6) is None


def test_elsewhere_only_a_log_with_nothing_in_flight_proves_the_line():
    quiet = ResumePoint(1, 2.0, _frames(TARGET, 8), confirmed=7, done=7)
    assert quiet.line_for((0.0, 0.0, 0.0), (None,) * 6) == 8
    in_flight = ResumePoint(1, 2.0, _frames(TARGET, 8), confirmed=7, done=4)
    with pytest.raises(NotProven):
        in_flight.line_for((221.0, 10.0, 280.0), (None,) * 6)
    assert ResumePoint(3, 2.0).line_for(None, (None,) * 6) == 3  # nothing was written: where it started


def test_a_joint_target_is_judged_by_the_joints():
    joint = {"kind": "joint", "xyz_mm": [0, 0, 0], "joints_deg": [10, 0, 0, 0, 0, 0]}
    point = ResumePoint(1, 2.0, (FrameEntry(1, 1, 1, 2, ELSEWHERE), FrameEntry(2, 2, 2, 3, joint)), confirmed=2, done=1)
    assert point.line_for((5.0, 5.0, 5.0), (10.1, 0, 0, 0, 0, 0)) == 3
    with pytest.raises(NotProven):
        point.line_for((0.0, 0.0, 0.0), (11.0, 0, 0, 0, 0, 0))


def test_a_log_of_another_or_an_edited_script_is_refused(tmp_path):
    log = tmp_path / "job.log"
    result = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--no-live", "--log", str(log)])
    assert result.exit_code == 0, result.output
    assert read_resume_lines(io.StringIO(log.read_text()), str(SHORT), SHORT.read_bytes()).sent_line == 6
    edited = tmp_path / "short_job.txt"
    edited.write_bytes(SHORT.read_bytes() + b"G1 X230\n")
    for script in (edited, SCRIPTS / "resume_job.txt"):
        completed = subprocess.run([*ARMCTL, "run", str(script), "--port", FAST_SIM, "--no-live", "--resume", str(log)],
                                   capture_output=True, text=True, timeout=60)
        assert completed.returncode == 2, completed.stderr
        assert "other contents" in completed.stderr and "Traceback" not in completed.stderr
    with pytest.raises(ResumeRefused):
        read_resume_lines(["not json\n"], "x", b"")
    both = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--resume", str(log), "--from-line", "3"])
    assert both.exit_code == 2 and "drop --from-line" in both.output


def test_resuming_a_finished_job_sends_nothing(tmp_path):
    log = tmp_path / "job.log"
    first = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--no-live", "--log", str(log)])
    assert first.exit_code == 0, first.output
    again = CliRunner().invoke(main, ["run", str(SHORT), "--port", FAST_SIM, "--no-live", "--resume", str(log)])
    assert again.exit_code == 0, again.output
    assert "nothing to resume" in again.stdout and "frames:" not in again.stdout


# --- kill -9 mid-job, then --resume against the same arm -----------------------------------------

CRASH_LINES = 24


def _crash_script(path: Path) -> Path:
    """Distinct moves (X and PWM differ on every line), each about 0.1 s of arm time, from the
    simulator's start (fixed pose 0: X210 Y0 Z300)."""
    lines = ["G1 X210 Y0 Z300 A180 B0 C0 S1000 F2400"]
    lines += [f"G1 X{210 + 4 * k} S{1000 + 10 * k}" for k in range(1, CRASH_LINES)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _wait_for(predicate, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return False


@pytest.mark.realtime
def test_kill_9_mid_job_then_resume_runs_every_line_exactly_once(tmp_path):
    script, log = _crash_script(tmp_path / "crash.txt"), tmp_path / "crash.log"
    # the arm's FIFO size as `armctl probe --write` records it: on a device path `done` needs it
    profile = tmp_path / "arm.toml"
    profile.write_text("[connector]\nfifo_frames = 200\n")
    arm = SimulatedArm(SimOptions())
    stop, ready = threading.Event(), []
    bridge = threading.Thread(target=serve_pty, args=(SimOptions(), ready.append, stop),
                              kwargs={"model": arm, "keep_serving": True}, daemon=True)
    bridge.start()
    try:
        assert _wait_for(lambda: ready, 5.0)
        host = subprocess.Popen([*ARMCTL, "run", str(script), "--port", ready[0], "--no-live", "--lead", "0.5",
                                 "--profile", str(profile), "--log", str(log)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            def proven_some():
                text = log.read_text() if log.exists() else ""
                return re.search(r'"done_line": [5-9]\b', text) is not None  # mid-job: line 5 or later known done
            assert _wait_for(proven_some, 30.0), log.read_text() if log.exists() else "no log"
            host.send_signal(signal.SIGKILL)
            host.wait(timeout=10)
        finally:
            host.kill()
        records = [json.loads(line) for line in log.read_text().splitlines()]
        written = [r for r in records if r["dir"] == "tx"]
        assert 0 < len(written) < CRASH_LINES  # killed mid-job
        done_at_kill = [r for r in records if r["dir"] == "progress"][-1]["done_line"]
        # the resumed host in this process (the killed one was a process of its own)
        resumed = CliRunner().invoke(main, ["run", str(script), "--port", ready[0], "--no-live", "--lead", "0.5",
                                            "--profile", str(profile), "--resume", str(log)])
        assert resumed.exit_code == 0, resumed.output
        assert "finished: the arm finished the job" in resumed.stdout
        resumed_at = int(re.search(r"resuming .* at line (\d+)", resumed.stderr).group(1))
        assert resumed_at > done_at_kill + 1  # the frames in flight at the kill ran: the arm's report proved it
    finally:
        stop.set()
        bridge.join(5.0)
    executed = [e.command for e in arm.execution_log if e.command is not None]
    expected = [decode_command(bytes.fromhex(r["hex"])) for r in _compiled(script)]
    assert executed == expected  # every line once, in order: none repeated, none skipped


def _compiled(script: Path) -> list[dict]:
    result = CliRunner().invoke(main, ["compile", str(script), "--format", "json"])
    assert result.exit_code == 0, result.output
    return [json.loads(line) for line in result.stdout.splitlines()]


def test_json_control_events_follow_the_view():
    """paused/resumed/override events from the view's control state (what the engine sets)."""
    import io
    from types import SimpleNamespace

    from armctl.ui.run_json import JsonEvents

    out = io.StringIO()
    events = JsonEvents(out, clock=lambda: 0.0)
    view = SimpleNamespace(total_frames=3, estimated_job_s=1.0, lead_s=2.0, frames_sent=1, last_sent=None, last_done=None,
                           elapsed_s=0.0, eta_s=1.0, position_mm=None, pause_state="running", feed_percent=100,
                           feed_clamped=False)
    events.started(view, "job.txt", 1)
    for state, percent in [("pausing", 100), ("paused", 100), ("paused", 120), ("resuming", 120), ("running", 120)]:
        view.pause_state, view.feed_percent = state, percent
        events.update(view)
    told = [json.loads(line)["event"] for line in out.getvalue().splitlines()]
    assert [e for e in told if e != "progress"] == ["started", "paused", "override", "resumed"]


def test_resume_from_an_endless_file_is_refused_not_read_forever(tmp_path):
    """--resume reads its log bounded, as every input: /dev/zero (zeros without a line break, no
    end) is exit 2 with a message, not a hang or a MemoryError."""
    script = tmp_path / "job.txt"
    script.write_text("G1 X200 Y0 Z250 A180 B0 C0 S1500 F3000\n")
    done = subprocess.run([*ARMCTL, "run", str(script), "--resume", "/dev/zero", "--port", "sim://?clock=virtual"],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    # issue 22: a device is refused before it is opened; a regular file is read bounded all the same
    assert "--resume /dev/zero: a character device, not a regular file" in done.stderr and "Traceback" not in done.stderr
