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

from armctl import Arm, ResumeRefused

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
