"""Review 7: what ``armctl status --watch`` and ``armctl run`` show a user.

1. ``status --watch`` (and ``--once``) on a noisy line printed the first report of each kind as read: on
   ``sim://?noise=0.05&corrupt=0.05&seed=2`` the first joints 4-6 report is corrupted (J5 reads
   322.96°, the arm is at 90°), and the plausibility rule (armctl/core/armstate.py) judges a kind
   only against an earlier report, so that first line showed a value the arm never reported.
   The first reading shown is now the one a job would start from (armctl/host/jobflow.py
   ``read_arm``: every kind, two more rotations, two states a rotation apart agreeing).
2. ``run --json`` interrupted while the job waits for the arm to rest (before its first frame)
   gave ``total_frames`` 0 in its summary, though the job has its frames: the summary now counts
   them (``CheckedScript.frames``, the estimate's count) and says 0 were sent.

Each runs the installed command in a fresh process (SIGINT with the default handler restored),
every wait bounded; the simulator's faults are seeded, so the corrupted report is the same one
in every run.
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = [sys.executable, "-m", "armctl"]
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}
WAIT_S = 20  # upper bound for any one wait; a healthy run takes a fraction of it
# seed 2: the first joints 4-6 report is corrupted (J5 322.96°); the arm stands at its home pose
NOISY = "noise=0.05&corrupt=0.05&seed=2"
# --timeout counts the port's model seconds: 2 s at speed=20 is 0.1 s of wall time, which a loaded
# machine overruns (the reads of two more rotations then end early); 60 is 3 s of wall time
MODEL_TIMEOUT = "60"
HOME = {"x": 210.0, "y": 0.0, "z": 300.0, "joints": [0.0, 0.0, 0.0, 0.0, 90.0, 0.0], "worktable": [0.0, 0.0, 0.0]}


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _spawn(arguments, **kwargs):
    return subprocess.Popen([*ARMCTL, *arguments], preexec_fn=_default_sigint, cwd=ROOT, **kwargs)


def _readline(stream) -> str:
    ready, _, _ = select.select([stream], [], [], WAIT_S)
    assert ready, "no output within the wait bound"
    return stream.readline()


def _pose(record: dict) -> dict:
    return {key: record[key] for key in HOME}


def _at_home(record: dict) -> bool:
    """Position, joints and worktable within a reading's jitter of the home pose (the engine's
    rule, ``moved_clearly``: what ``read_arm`` proves; a corrupted report within the arm's reach
    may pass it by less)."""
    from armctl.core.job_readings import moved_clearly

    def pose(r):
        return (r["x"], r["y"], r["z"]), tuple(r["joints"][:3]), tuple(r["joints"][3:])

    return not moved_clearly(pose(record), pose(HOME)) and record["worktable"] == HOME["worktable"]


def test_the_home_pose_is_what_a_clean_line_reports():
    """The reference the noisy runs are compared with."""
    out = subprocess.run([*ARMCTL, "status", "--once", "--json", "--port", "sim://?clock=virtual"], cwd=ROOT, env=ENV,
                         capture_output=True, text=True, timeout=WAIT_S)
    assert out.returncode == 0, out.stderr
    assert _pose(json.loads(out.stdout)) == HOME  # (virtual time: the same reports in every run)


@pytest.mark.realtime
def test_watch_json_first_line_is_no_corrupted_report():
    process = _spawn(["status", "--watch", "--json", "--port", f"sim://?speed=20&{NOISY}", "--timeout", MODEL_TIMEOUT], env=ENV,
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = _readline(process.stdout)
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=WAIT_S)
        err = process.stderr.read()
    finally:
        process.kill()
    assert code == 130, err
    assert _at_home(json.loads(first)), first


@pytest.mark.realtime
def test_watch_live_panel_never_shows_the_corrupted_report():
    master, slave = os.openpty()
    try:
        process = _spawn(["status", "--watch", "--port", f"sim://?speed=20&{NOISY}", "--timeout", MODEL_TIMEOUT],
                         stdin=slave, stdout=slave,
                         stderr=slave, env={**ENV, "TERM": "xterm-256color", "COLUMNS": "120", "LINES": "40"})
    finally:
        os.close(slave)
    output = b""
    try:
        deadline = time.monotonic() + WAIT_S
        while b"90.00" not in output and time.monotonic() < deadline:  # until the panel shows the arm's J5
            if select.select([master], [], [], 0.1)[0]:
                output += os.read(master, 65536)
        time.sleep(0.3)  # a few more panels (some 5 rotations of the arm at speed=20)
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=WAIT_S)
        while select.select([master], [], [], 0.2)[0]:
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: the child closed the pty
                break
            if not chunk:
                break
            output += chunk
    finally:
        process.kill()
        os.close(master)
    text = output.decode("utf-8", "replace")
    assert code == 130, text[-500:]
    assert "90.00" in text, text[-500:]
    assert "322.96" not in text


def test_once_json_is_no_corrupted_report():
    out = subprocess.run([*ARMCTL, "status", "--once", "--json", "--port", f"sim://?clock=virtual&{NOISY}"], cwd=ROOT,
                         env=ENV, capture_output=True, text=True, timeout=WAIT_S)
    assert out.returncode == 0, out.stderr
    assert _pose(json.loads(out.stdout)) == HOME  # (virtual time: the same reports in every run)


# --- 2. run --json: Ctrl-C while the job waits for the arm to rest ------------------------------


def _summary(stdout: str) -> dict:
    summary = json.loads(stdout.splitlines()[-1])
    assert summary["event"] == "summary", stdout
    return summary


@pytest.mark.realtime
def test_ctrl_c_while_the_job_waits_for_rest_gives_the_job_s_total(tmp_path):
    """The installed command on ``armctl sim --pty`` (its own process, 2x time), a 20 s move
    written to it just before: the job waits for the arm to rest; SIGINT then.  The summary says
    nothing was sent, of the job's frames — as many as a run of it on a still arm has."""
    from journal_crash import pty_arm
    from test_moving_start import _leftover
    from test_review5_moving_start import JOB, WAITING

    (tmp_path / "job.txt").write_text(JOB)
    env = {**ENV, "XDG_DATA_HOME": str(tmp_path / "data")}
    whole = subprocess.run([*ARMCTL, "run", "job.txt", "--json", "--port", "sim://?clock=virtual"], cwd=tmp_path,
                           env=env, capture_output=True, text=True, timeout=WAIT_S)
    total = _summary(whole.stdout)["total_frames"]
    assert whole.returncode == 0 and total == 2, whole.stderr
    with pty_arm("--url", "sim://?speed=2", env=env) as pty:
        with open(pty, "wb", buffering=0) as line:
            line.write(b"".join(_leftover(300)))
        time.sleep(0.3)
        run = subprocess.Popen([*ARMCTL, "run", "job.txt", "--json", "--port", pty], cwd=tmp_path, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)
        told = []
        for text in run.stderr:  # until armctl says it waits (within the move's 10 s of wall time)
            told.append(text)
            if WAITING in text:
                break
        run.send_signal(signal.SIGINT)
        out, err = run.communicate(timeout=WAIT_S)
    assert WAITING in "".join(told), "".join(told) + err
    assert run.returncode == 130, err
    summary = _summary(out)
    assert (summary["outcome"], summary["frames_sent"], summary["total_frames"]) == ("interrupted", 0, total), summary


@pytest.mark.parametrize("text, from_line", [
    ("G90\nG1 X360 Y0 Z150 A180 B0 C0 S1000 F3000\nG6 J1=-7.6 J2=11.4 J3=-7.9 J4=0 J5=90 J6=0 F30\n", 1),
    ("G90\nO1 repeat [40]\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260 Y0 Z150 A180 B0 C0 S1000 F3000\n"
     "O1 endrepeat\nG91\nG1 X1\nG1 X-1\n", 1),
    ("G90\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260\nG1 X270\nG4 P0.5\nG1 X280\n", 3),
])
def test_a_checked_job_counts_the_frames_its_plan_sends(text, from_line):
    """``CheckedScript.frames`` (the total a job stopped before it was planned reports) is the
    estimate's count of the frames the job sends, from the arm's start as from the fixed pose."""
    from armctl.core.checked import check, plan, start_at
    from armctl.core.motion import MotionModel
    from armctl.host.profile import load_profile
    from armctl.script.files import ScriptSnapshot

    profile = load_profile(None)
    checked = check(ScriptSnapshot("job.txt", text.encode()), profile, from_line=from_line)
    assert checked.refusal() is None
    model = MotionModel(profile)
    assert checked.frames() == plan(checked, model, *start_at(model), 0.5, 9600).estimate.frames > 0
