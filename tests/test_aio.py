"""``armctl.aio.AsyncArm``: ``Arm``'s semantics as coroutines (in-process, virtual time where
time does not matter)."""
from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from armctl import ScriptError
from armctl.aio import AsyncArm

pytestmark = pytest.mark.timeout(60)

SHORT = (Path(__file__).parent / "data" / "scripts_cli" / "short_job.txt").read_text()
VIRTUAL = "sim://?clock=virtual"


def slow_job(moves: int = 30) -> str:
    return "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n" + "".join(
        f"G1 X{250 + (i % 2) * 40} Y{(i % 3) * 20} F2400\n" for i in range(moves))


async def streaming(arm):
    """``slow_job`` started on ``arm``, once its first frame went: the task awaiting it."""
    started = asyncio.Event()
    job = asyncio.ensure_future(arm.run(slow_job(), on_event=lambda e: e["event"] == "started" and started.set()))
    await asyncio.wait_for(started.wait(), 20)
    return job


def test_run_gives_the_run_json_events_on_the_loop_and_the_same_result_as_arm_run():
    from armctl import Arm
    async def main():
        events, threads = [], set()
        import threading

        def on_event(event):
            threads.add(threading.current_thread())
            events.append(event)

        async with await AsyncArm.open(VIRTUAL) as arm:
            result = await arm.run(SHORT, on_event=on_event)
        return result, events, threads

    result, events, threads = asyncio.run(main())
    import threading

    assert threads == {threading.main_thread()}  # every event handed to the loop's thread
    assert [e["event"] for e in events][0] == "started" and events[-1]["event"] == "summary"
    assert events[-1] == {"event": "summary", **result.to_json()}
    with Arm.open(VIRTUAL) as arm:
        blocking = arm.run(SHORT)
    assert result == blocking  # the same engine, the same virtual-time arm: the same result


def test_move_status_and_a_bad_script_sends_nothing():
    async def main():
        async with await AsyncArm.open(VIRTUAL) as arm:
            done = await arm.move(x=230, y=0, z=200, a=180, b=0, c=0, f=3000)
            assert done.finished and done.last_line_executed == 1
            status = await arm.status()
            assert status.position_mm == pytest.approx((230, 0, 200), abs=0.1)
            report = await arm.status_json()
            assert report["x"] == pytest.approx(230, abs=0.1)
            with pytest.raises(ScriptError) as refused:
                await arm.run("G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 Z\n")
            assert refused.value.diagnostics[0].span.line == 2
            after = await arm.status()
            assert after.position_mm == status.position_mm

    asyncio.run(main())


@pytest.mark.realtime
def test_pause_resume_feed_and_stop_while_run_awaits():
    async def main():
        async with await AsyncArm.open("sim://?speed=20") as arm:
            job = await streaming(arm)
            assert await arm.feed_override(150) == 150
            assert await arm.pause() is True
            assert await arm.resume() is True
            await arm.stop()
            result = await asyncio.wait_for(job, 30)
            assert result.outcome == "interrupted" and result.frames_sent < result.total_frames

    asyncio.run(main())


@pytest.mark.realtime
def test_cancelling_the_awaiting_task_stops_the_arm():
    async def main():
        async with await AsyncArm.open("sim://?speed=20") as arm:
            job = await streaming(arm)
            job.cancel()
            with pytest.raises(asyncio.CancelledError):
                await job
            again = await arm.run(SHORT)  # the arm is free again: the job really ended
            assert again.finished

    asyncio.run(main())


def test_two_arms_run_at_once_on_one_loop():
    async def main():
        async with await AsyncArm.open(VIRTUAL) as first, await AsyncArm.open(VIRTUAL) as second:
            return await asyncio.gather(first.run(SHORT), second.run(SHORT))

    results = asyncio.run(main())
    assert [r.outcome for r in results] == ["finished", "finished"]


def test_a_refused_resume_raises_before_anything_with_no_event():
    from armctl.errors import ResumeRefused

    async def main():
        events = []
        async with await AsyncArm.open(VIRTUAL) as arm:
            with pytest.raises(ResumeRefused):
                await arm.run(SHORT, resume="/nonexistent/log", on_event=events.append)
        return events

    assert asyncio.run(main()) == []  # refused before anything: no event, nothing sent
