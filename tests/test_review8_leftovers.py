"""Review 8: faults the first reviews of this session reported and left.

1. A stop that comes before the job's first frame — ``arm.stop()`` from an observer's
   ``started()``, or Ctrl-C of ``armctl run`` between the arm's check and the first frame — sent
   the abort sequence's pause toggle to an arm that was sent nothing of the job, and left it
   paused.  Nothing of the job is queued then: nothing is sent, the arm is left as it was, the
   job ends "interrupted" at its first line.
2. A resume refused by the journal's reader (armctl/core/joblog.py: no job record, resumed already,
   a format-1 log, the arm not where the log leaves it) named ``armctl run``'s ``--from-line`` and
   ``--resume`` to a program that called ``Arm.run(resume=)`` (the server's side:
   tests/test_serve_review8.py).
3. An exception an observer's ``warning()`` or ``note()`` raised before the first frame came out of
   ``Arm.run`` raw (``started()``'s ends the job: tests/test_review7_api.py): now the same —
   ``JobFailed`` from it, outcome "failed", nothing sent, the arm left as it was.
4. ``Arm.run``'s result for a job stopped while it waits for a moving arm to rest (before its first
   frame) gave ``total_frames`` 0, though the job has its frames (``armctl run --json`` counts
   them: tests/test_review7_watch.py): the API's result counts them too.

In virtual time (``sim://?clock=virtual``) in-process; the installed command in a fresh process
on ``armctl sim --pty`` (its own process, so what it was sent is counted there).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from armctl import Arm, JobFailed, JobObserver

pytestmark = pytest.mark.timeout(30)

VIRTUAL = "sim://?clock=virtual"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260\n"
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}


def received(arm: Arm) -> list:
    return [type(frame.command).__name__ for frame in arm._link.port.model.frames_received]


@pytest.fixture
def job(tmp_path) -> Path:
    path = tmp_path / "job.txt"
    path.write_text(JOB)
    return path


# -- 1. a stop before the first frame sends nothing -----------------------------------------------

class _StopsAtStart(JobObserver):
    def __init__(self, arm: Arm) -> None:
        self.arm, self.notes = arm, []

    def started(self, view, plan) -> None:
        self.arm.stop()

    def note(self, text: str) -> None:
        self.notes.append(text)


@pytest.mark.parametrize("abort", ["pause", "reset-connector"])
def test_a_stop_in_started_sends_nothing_and_leaves_the_arm_as_it_was(job, abort):
    with Arm.open(VIRTUAL) as arm:
        observer = _StopsAtStart(arm)
        result = arm.run(job, observer=observer, abort=abort)
        assert result.outcome == "interrupted" and result.frames_sent == 0 and result.resume_line == 1, result
        assert result.total_frames == 2, result
        arm._call(lambda: arm._link.wait_until(lambda state: False, 2.0))  # 2 s of the arm's clock
        assert received(arm) == []
        assert arm.status().paused is False
        assert not any("sending the abort sequence" in note for note in observer.notes), observer.notes
        again = arm.run(job)
        assert again.finished and again.frames_sent == 2
        assert received(arm) == ["LinearMove", "LinearMove"]  # no resume toggle: it was never paused


def _served_arm(stats: Path) -> tuple[subprocess.Popen, str]:
    """``armctl sim --pty --stats`` in its own process: what the arm was sent is counted there."""
    sim = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--stats", str(stats)],
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=ENV)
    line = sim.stdout.readline()  # "simulated arm on /dev/pts/N (Ctrl-C to stop)"
    return sim, line.split(" on ", 1)[1].split(" ", 1)[0]


# armctl's own entry, with a real SIGINT delivered to it just after the job's observer started (the
# job checked, the arm read, the panel set up): the instant before the first frame, held open long
# enough for run's signal handler to take it (arm.stop(), as any Ctrl-C once the job has started)
CTRL_C_AT_START = """
import os, signal, sys, time
import armctl.ui.run_job as run_job
original = run_job._RunObserver.started
def started(self, view, plan):
    original(self, view, plan)
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(1.0)
run_job._RunObserver.started = started
sys.argv[0] = "armctl"
from armctl.__main__ import main
main()
"""


@pytest.mark.realtime
@pytest.mark.timeout(90)
def test_ctrl_c_of_armctl_run_before_the_first_frame_sends_nothing(job, tmp_path):
    stats = tmp_path / "stats.json"
    sim, pty = _served_arm(stats)
    try:
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(CTRL_C_AT_START), "run", str(job), "--port", pty,
                               "--no-live"], capture_output=True, text=True, timeout=60, env=ENV, cwd=tmp_path,
                              stdin=subprocess.DEVNULL)
        status = subprocess.run([sys.executable, "-m", "armctl", "status", "--once", "--json", "--port", pty],
                                capture_output=True, text=True, timeout=30, env=ENV)
    finally:
        sim.send_signal(signal.SIGINT)
        sim.wait(timeout=30)
    assert "Traceback" not in done.stderr, done.stderr
    assert done.returncode == 130, (done.returncode, done.stdout, done.stderr)
    assert "frames: 0 of 2 sent" in done.stdout, done.stdout
    assert "sending the abort sequence" not in done.stderr, done.stderr
    assert "stopped: interrupted before the first frame" in done.stderr, done.stderr
    assert status.returncode == 0 and json.loads(status.stdout)["paused"] is False, status.stdout
    assert json.loads(stats.read_text())["frames"] == []  # nothing landed at the arm


# -- 2. a refused resume in the API's words -------------------------------------------------------

CLI_WORDS = ("--resume", "--from-line", "--log", "--port")


def _journal(tmp_path: Path, job: Path, stop_after: int) -> Path:
    """A ``log=`` journal of ``job`` stopped after its frame ``stop_after`` (virtual time)."""
    log = tmp_path / "stopped.log"
    with Arm.open(VIRTUAL) as arm, open(log, "w", encoding="utf-8") as file:
        result = arm.run(job, log=file, on_progress=lambda p: p.frames_sent >= stop_after and arm.stop())
    assert result.outcome == "interrupted" and result.frames_sent == stop_after, result
    return log


def _refusals(tmp_path: Path, job: Path) -> dict:
    """Each refusal of the journal's reader, as ``Arm.run(resume=)`` meets it: (type, message)."""
    from armctl.core.joblog import job_record, seal
    from armctl.host.jobflow import mark_resumed

    logs = {"no job record": "", "format 1": '{"t": 0.0, "dir": "job", "script": "job.txt"}\n'}
    for name, text in logs.items():
        (tmp_path / f"{name}.log").write_text(text)
    once = tmp_path / "resumed already.log"
    once.write_text(seal(job_record(str(job), job.read_bytes(), 1, 2.0), 0) + "\n")
    mark_resumed(str(once), 1, None)  # resumed once, by a run that kept no journal
    stopped = _journal(tmp_path, job, 2)
    # the journal up to the second frame's progress record: nothing proven done; the arm, moved, is
    # neither where the job started nor where line 1 or 2 leaves it
    kept = stopped.read_text().splitlines(keepends=True)
    last = min(i for i, line in enumerate(kept) if '"dir": "progress"' in line and '"frames_sent": 2' in line)
    (tmp_path / "not proven.log").write_text("".join(kept[:last + 1]))
    answers = {}
    with Arm.open(VIRTUAL) as arm:
        arm.move(x=200, y=50, z=200, f=3000)
        moved = len(received(arm))
        for name in ("no job record", "format 1", "resumed already", "not proven"):
            with pytest.raises(Exception) as refused:
                arm.run(job, resume=tmp_path / f"{name}.log")
            answers[name] = (type(refused.value).__name__, str(refused.value))
        assert len(received(arm)) == moved  # nothing sent by the resumes
    return answers


def test_the_journal_s_refusals_speak_the_api_words(job, tmp_path):
    answers = _refusals(tmp_path, job)
    assert {name: kind for name, (kind, _) in answers.items()} == {
        "no job record": "ResumeRefused", "format 1": "ResumeRefused", "resumed already": "ResumeRefused",
        "not proven": "NotProven"}
    for name, (_, message) in answers.items():
        assert not any(word in message for word in CLI_WORDS), (name, message)
        assert "from_line" in message, (name, message)
    assert "resume=" in answers["no job record"][1]


# -- 3. an observer's warning() or note() that raises before the first frame ---------------------

class _Raises(JobObserver):
    def __init__(self, where: str) -> None:
        self.where, self.error, self.updates = where, ValueError(f"no room for a {where}"), 0

    def warning(self, diagnostic) -> None:
        if self.where == "warning":
            raise self.error

    def note(self, text: str) -> None:
        if self.where == "note":
            raise self.error

    def update(self, view) -> None:
        self.updates += 1


def _failed_by(observer: _Raises, run) -> object:
    with pytest.raises(JobFailed) as failed:
        run()
    assert failed.value.__cause__ is observer.error, failed.value
    assert f"the observer's {observer.where}() raised ValueError: no room for a {observer.where}" in str(failed.value)
    result = failed.value.result
    assert result.outcome == "failed" and result.frames_sent == 0 and result.exit_code == 1, result
    assert observer.updates == 0
    return result


def test_a_warning_that_raises_fails_the_job_with_nothing_sent(tmp_path):
    job = tmp_path / "warned.txt"
    job.write_text("#<unused> = 5\n" + JOB)  # L401: assigned but never read (a warning)
    observer = _Raises("warning")
    with Arm.open(VIRTUAL) as arm:
        result = _failed_by(observer, lambda: arm.run(job, observer=observer))
        assert result.resume_line == 1, result
        arm._call(lambda: arm._link.wait_until(lambda state: False, 2.0))  # 2 s of the arm's clock
        assert received(arm) == [] and arm.status().paused is False
        assert arm.run(job).finished


def test_a_note_that_raises_fails_the_job_and_leaves_a_paused_arm_paused(job):
    observer = _Raises("note")
    with Arm.open(VIRTUAL) as arm:
        assert arm.pause() and arm.status().paused  # the run finds the arm paused: it notes the toggle it sends
        before = received(arm)
        result = _failed_by(observer, lambda: arm.run(job, observer=observer))
        assert result.resume_line == 1, result
        assert received(arm) == before and arm.status().paused is True  # left as it was
        assert arm.run(job).finished


def test_a_note_that_raises_in_a_resume_fails_it_and_the_log_can_be_resumed(job, tmp_path):
    log = tmp_path / "job.log"
    with Arm.open(VIRTUAL) as arm:
        with open(log, "w", encoding="utf-8") as file:
            stopped = arm.run(job, log=file, on_progress=lambda p: p.frames_sent >= 1 and arm.stop())
        assert stopped.outcome == "interrupted" and stopped.frames_sent == 1, stopped
        before = received(arm)
        observer = _Raises("note")
        _failed_by(observer, lambda: arm.run(job, resume=log, observer=observer))
        assert received(arm) == before
        resumed = arm.run(job, resume=log)  # the log was not marked resumed: nothing of it ran
        assert resumed.finished and resumed.frames_sent == 1, resumed


# -- 4. the total of a job stopped while it waits for the arm to rest -----------------------------

# a program that leaves a slow move queued (another program's, a crashed armctl's), then runs a job
# and stops it when the job says it waits for the arm to rest: the result, with nothing sent
STOPPED_WHILE_WAITING = """
from armctl import Arm, JobObserver
from armctl.core.protocol import LinearMove
with Arm.open("sim://?clock=virtual") as arm:
    class Waits(JobObserver):
        def note(self, text):
            if "the arm is moving" in text:
                arm.stop()
    frame = LinearMove(250, 0, 150, 180, 0, 0, 1500, 300).encode()
    arm._call(lambda: arm._link.write(frame))
    result = arm.run("job.txt", observer=Waits())
    print(result.outcome, result.frames_sent, result.total_frames, len(arm._link.port.model.frames_received))
"""


def test_a_job_stopped_while_the_arm_comes_to_rest_gives_its_total(job):
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(STOPPED_WHILE_WAITING)], capture_output=True, text=True,
                          timeout=25, cwd=job.parent, env=ENV)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["interrupted", "0", "2", "1"], done.stdout  # the other's move alone was sent


class _StopsAtWarning(JobObserver):
    def __init__(self, arm: Arm) -> None:
        self.arm = arm

    def warning(self, diagnostic) -> None:
        self.arm.stop()  # while the job is being planned: nothing goes


def test_a_job_stopped_while_it_is_planned_gives_its_total(tmp_path):
    job = tmp_path / "warned.txt"
    job.write_text("#<unused> = 5\n" + JOB)
    with Arm.open(VIRTUAL) as arm:
        result = arm.run(job, observer=_StopsAtWarning(arm))
        assert (result.outcome, result.frames_sent, result.total_frames) == ("interrupted", 0, 2), result
        assert received(arm) == []
