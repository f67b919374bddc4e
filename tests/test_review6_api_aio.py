"""Review of ``armctl.aio.AsyncArm`` as an asyncio program meets it: an ``on_event`` that raises,
a call after ``close()``.  In virtual time (``sim://?clock=virtual``)."""
from __future__ import annotations

import asyncio

import pytest

from armctl import ArmctlError, JobFailed
from armctl.aio import AsyncArm
from armctl.core.protocol import PauseToggle

pytestmark = pytest.mark.timeout(30)

VIRTUAL = "sim://?clock=virtual"
LONG_JOB = "G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [30]\nG1 Z100 F3000\nG1 Z150\nO<a> endrepeat\n"


def test_a_call_after_close_says_the_arm_is_closed():
    async def main():
        arm = await AsyncArm.open(VIRTUAL)
        await arm.close()
        await arm.close()  # twice: nothing more
        for call in (arm.status, lambda: arm.run("G4 P10\n"), lambda: arm.move(x=250), arm.pause):
            with pytest.raises(ArmctlError, match="closed"):
                await call()

    asyncio.run(main())


def test_an_on_event_that_raises_stops_the_job_as_on_progress_does():
    logged = []

    async def main():
        asyncio.get_running_loop().set_exception_handler(lambda loop, context: logged.append(context))
        async with await AsyncArm.open("sim://?speed=10") as arm:  # (the job's 20 s of arm time: 2 s)
            def on_event(event):
                if event["event"] == "progress":
                    raise KeyError("a bug in on_event")

            with pytest.raises(JobFailed, match="on_event") as failed:
                await arm.run(LONG_JOB, on_event=on_event)
            assert isinstance(failed.value.__cause__, KeyError)
            result = failed.value.result
            assert result.frames_sent < result.total_frames
            frames = arm.arm._link.port.model.frames_received
            assert sum(isinstance(frame.command, PauseToggle) for frame in frames) == 1

    asyncio.run(main())
    assert logged == []


def test_async_move_refuses_wait_and_sends_nothing():
    async def main():
        async with await AsyncArm.open(VIRTUAL) as arm:
            with pytest.raises(TypeError, match="wait"):
                await arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
            assert arm.arm._link.port.model.frames_received == []

    asyncio.run(main())


@pytest.mark.parametrize("script", [3, None])
def test_async_run_with_on_event_names_a_script_of_the_wrong_type(script):
    async def main():
        async with await AsyncArm.open(VIRTUAL) as arm:
            with pytest.raises(TypeError, match="^script must be a path"):
                await arm.run(script, on_event=lambda event: None)

    asyncio.run(main())
