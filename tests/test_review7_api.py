"""Review of the Python API (``armctl.Arm``, ``armctl.aio``) as a programmer meets it: a
``resume=`` that names no journal, refusals of a resume in words the API does not have, an
observer whose ``started`` raises, arms opened in a loop and never closed.

In virtual time (``sim://?clock=virtual``), and a fresh process where what a program sees matters.
"""
from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import textwrap

import pytest

from armctl import Arm, JobFailed, JobObserver, ResumeRefused

pytestmark = pytest.mark.timeout(30)

VIRTUAL = "sim://?clock=virtual"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z120\nG1 Z100\n"


def received(arm: Arm) -> list:
    return [frame.command for frame in arm._link.port.model.frames_received]


def run_program(program: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(program)], capture_output=True, text=True,
                          timeout=25, cwd=cwd, env={**os.environ, "ARMCTL_PORT": VIRTUAL})


@pytest.fixture
def place(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "journals").mkdir()
    os.mkfifo(tmp_path / "pipe")
    return tmp_path


# -- 1. a resume= that names a directory (or a named pipe): ResumeRefused, as documented ------------

@pytest.mark.parametrize("what", ["journals", "pipe"])
def test_a_resume_of_no_regular_file_is_refused_as_a_resume(place, what):
    """``Arm.run(resume=DIR)`` raised ``NotARegularFile`` (armctl.host.inputs, not public), where
    docs/api.md lists ``ResumeRefused`` for a resume= that is not a log; nothing may be sent."""
    with Arm.open(VIRTUAL) as arm:
        with pytest.raises(ResumeRefused) as refused:
            arm.run(place / "job.txt", resume=place / what)
        assert str(place / what) in str(refused.value), refused.value
        assert received(arm) == []


def test_the_async_api_refuses_a_directory_as_a_resume(place):
    from armctl.aio import AsyncArm

    async def main() -> str:
        async with await AsyncArm.open(VIRTUAL) as arm:
            try:
                await arm.run(place / "job.txt", resume=place / "journals")
            except ResumeRefused as error:
                return str(error)
        return "not refused"

    assert str(place / "journals") in asyncio.run(main())


def test_a_program_catching_resume_refused_gets_it_for_a_directory(place):
    """As a program meets it, in a fresh process: the documented error, its message naming the path."""
    done = run_program("""
        from armctl import Arm, ResumeRefused
        with Arm.open() as arm:
            try:
                arm.run("job.txt", resume="journals")
            except ResumeRefused as error:
                print("refused:", error)
        """, place)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("refused:") and "journals" in done.stdout, done.stdout


# -- 2. a refused resume speaks the API's words, not armctl run's flags ------------------------------

CLI_WORDS = ("--resume", "--port", "--from-line", "--other-port")


def assert_api_words(message: str, log) -> None:
    assert f"resume={str(log)!r}" in message, message
    assert not any(flag in message for flag in CLI_WORDS), message


def _stopped_job_log(arm: Arm, place, name: str = "job.log"):
    """A job of ``place/job.txt`` stopped after its second frame, journalled to ``place/name``."""
    def stop(progress) -> None:
        if progress.frames_sent == 2:
            arm.stop()

    with open(place / name, "w", encoding="utf-8") as log:
        arm.run(place / "job.txt", on_progress=stop, log=log)
    return place / name


def test_a_resume_with_from_line_is_refused_in_the_api_words(place):
    with Arm.open(VIRTUAL) as arm:
        log = _stopped_job_log(arm, place)
        with pytest.raises(ResumeRefused) as refused:
            arm.run(place / "job.txt", resume=log, from_line=2)
    assert "from_line" in str(refused.value)
    assert_api_words(str(refused.value), log)


def test_a_resume_on_another_arm_is_refused_in_the_api_words(place):
    with Arm.open(VIRTUAL) as arm:
        log = _stopped_job_log(arm, place)
    with Arm.open(VIRTUAL + "&fifo_frames=150") as other:  # another arm: another FIFO
        with pytest.raises(ResumeRefused) as refused:
            other.run(place / "job.txt", resume=log)
        assert received(other) == []
    assert f"Arm.open({VIRTUAL!r})" in str(refused.value)  # where the arm its job ran on is
    assert_api_words(str(refused.value), log)


def test_a_resume_of_another_process_simulated_arm_is_refused_in_the_api_words(place):
    """The log of a job on a simulated arm of another process (a program run before this one)."""
    done = run_program("""
        from armctl import Arm
        with Arm.open() as arm:
            with open("job.log", "w", encoding="utf-8") as log:
                arm.run("job.txt", log=log)
        """, place)
    assert done.returncode == 0, done.stderr
    with Arm.open(VIRTUAL) as arm:
        with pytest.raises(ResumeRefused, match="does not outlive its process") as refused:
            arm.run(place / "job.txt", resume=place / "job.log")
        assert received(arm) == []
    assert "Arm.open(" in str(refused.value)  # how to open an arm kept in a process of its own
    assert_api_words(str(refused.value), place / "job.log")


def test_a_resume_of_a_journal_another_resume_holds_is_refused_in_the_api_words(place):
    from armctl.host.log_lock import resume_claim

    with Arm.open(VIRTUAL) as arm:
        log = _stopped_job_log(arm, place)
        with resume_claim(str(log)):  # another program resuming it now
            with pytest.raises(ResumeRefused, match="still running") as refused:
                arm.run(place / "job.txt", resume=log)
    assert_api_words(str(refused.value), log)


# -- 3. an observer whose started() raises: the job ends before its first frame, JobFailed from it ----

class _FailsToStart(JobObserver):
    def __init__(self, error: BaseException) -> None:
        self.error, self.updates = error, 0

    def started(self, view, plan) -> None:
        raise self.error

    def update(self, view) -> None:
        self.updates += 1


def test_an_observer_whose_started_raises_fails_the_job_with_nothing_sent(place):
    """docs/api.md: an exception an observer raises stops the job, as ``on_progress``'s does
    (``JobFailed``, outcome "failed", the exception as its cause).  ``started`` comes before the
    first frame: nothing is sent, the arm stays at rest, and the next job runs."""
    observer = _FailsToStart(ValueError("the panel could not be drawn"))
    with Arm.open(VIRTUAL) as arm:
        before = arm.status()
        with open(place / "job.log", "w", encoding="utf-8") as log:
            with pytest.raises(JobFailed) as failed:
                arm.run(place / "job.txt", observer=observer, log=log)
        assert failed.value.__cause__ is observer.error
        result = failed.value.result
        assert result.outcome == "failed" and result.frames_sent == 0 and result.resume_line == 1, result
        assert "ValueError: the panel could not be drawn" in str(failed.value), failed.value
        assert received(arm) == [] and observer.updates == 0
        arm._call(lambda: arm._link.wait_until(lambda state: False, 2.0))  # 2 s of the arm's clock: still at rest
        assert received(arm) == [] and arm.status().position_mm == before.position_mm and not arm.status().paused
        assert arm.run(place / "job.txt", resume=place / "job.log").finished  # the journal says: from line 1


def test_an_async_observer_whose_started_raises_fails_the_job(place):
    from armctl.aio import AsyncArm

    async def main():
        async with await AsyncArm.open(VIRTUAL) as arm:
            with pytest.raises(JobFailed) as failed:
                await arm.run(place / "job.txt", observer=_FailsToStart(RuntimeError("no screen")))
            return failed.value, received(arm.arm)

    error, sent = asyncio.run(main())
    assert isinstance(error.__cause__, RuntimeError) and error.result.outcome == "failed" and sent == []


def test_a_program_whose_observer_fails_to_start_is_told_so(place):
    """As a program meets it, in a fresh process: a ``JobFailed`` it can catch, naming what its observer raised."""
    done = run_program("""
        from armctl import Arm, JobFailed, JobObserver
        class Panel(JobObserver):
            def started(self, view, plan):
                raise KeyError("width")
        with Arm.open() as arm:
            try:
                arm.run("job.txt", observer=Panel())
            except JobFailed as error:
                print("failed:", error.result.outcome, error.result.frames_sent, error)
        """, place)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("failed: failed 0") and "KeyError" in done.stdout, done.stdout


def test_an_interrupt_in_started_leaves_with_nothing_sent(place):
    """Ctrl-C (``KeyboardInterrupt``) or ``sys.exit()`` in ``started`` is not turned into ``JobFailed``:
    it leaves ``run`` as raised — before the first frame, so nothing was sent."""
    with Arm.open(VIRTUAL) as arm:
        with pytest.raises(KeyboardInterrupt):
            arm.run(place / "job.txt", observer=_FailsToStart(KeyboardInterrupt()))
        assert received(arm) == []
        assert arm.run(place / "job.txt").finished


# -- 6. an arm nobody holds is closed, not kept until the program exits -------------------------------

def _workers() -> list:
    import threading

    return [thread for thread in threading.enumerate() if thread.name.startswith("armctl-arm ")]


def _until(condition, timeout_s: float = 10.0) -> bool:
    import time

    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_arms_opened_in_a_loop_and_dropped_are_not_kept():
    import gc
    import weakref

    before = len(_workers())
    links = []
    for _ in range(20):
        arm = Arm.open(VIRTUAL)
        arm.move(z=200, f=3000)
        links.append(weakref.ref(arm._link))
        del arm
    gc.collect()
    assert _until(lambda: len(_workers()) <= before), f"{len(_workers()) - before} arms' workers left running"
    gc.collect()
    assert sum(link() is not None for link in links) == 0


def test_a_dropped_arm_still_runs_its_queued_moves():
    """An arm dropped with moves queued (``wait=False``) runs them, each once, then is closed."""
    import gc

    before = len(_workers())
    arm = Arm.open(VIRTUAL)
    model = arm._link.port.model
    arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
    arm.move(z=120, wait=False)
    del arm
    gc.collect()
    assert _until(lambda: len(_workers()) <= before)
    assert len(model.frames_received) == 2


def test_a_dropped_arm_whose_queued_move_failed_says_so(caplog):
    """As at the exit (tests/test_review6_api.py): the error of a queued move no call raised is
    said on the ``armctl.host.api`` logger, not dropped with the arm."""
    import gc
    import logging
    import weakref

    before = len(_workers())
    arm = Arm.open("sim://?clock=virtual&loss=1", status_timeout_s=0.2)  # every status frame lost
    arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
    tasks = weakref.ref(arm._tasks)
    del arm
    with caplog.at_level(logging.WARNING, logger="armctl.host.api"):
        assert _until(lambda: gc.collect() is not None and tasks() is None)
        assert _until(lambda: len(_workers()) <= before)
    assert "as the program dropped it; a move queued on it with wait=False failed: no complete status" in caplog.text
