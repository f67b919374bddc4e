"""Review of ``armctl serve`` as a workshop meets it: two clients on one arm, a double-clicked
Stop, the server stopped mid-job with a page open.  The installed command on a free loopback
port (tests/serve_process.py), or the app in this process where a moment must be held exactly.

A stop asked again while the job stops is, to ``Arm.stop``, a second Ctrl-C: the wait for the
arm to come to rest is cut short.  The server's stops (the run panel's Stop, a second client's,
the one ``armctl serve``'s own shutdown makes again when it closes the arm) are each one user's
one stop: the arm is always waited for, so a job shown as ended has its arm at rest and its
record's last line executed proven."""
from __future__ import annotations

import asyncio
import json
import signal
import time
from pathlib import Path

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

import aiohttp  # noqa: E402

from serve_process import served  # noqa: E402
from test_server_api import long_job  # noqa: E402

pytestmark = pytest.mark.timeout(60)

SLOW = "sim://?speed=4"  # a move of the long job: about 0.25 s of wall time


def _wait_frames(server, job_id: str, frames: int, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while server.request("GET", f"/api/arms/a/jobs/{job_id}")[1]["frames_sent"] < frames:
        assert time.monotonic() < deadline, f"job {job_id} did not send {frames} frames"
        time.sleep(0.02)


def _pose(server) -> tuple:
    status, report = server.request("GET", "/api/arms/a/status")
    assert status == 200, report
    return report["x"], report["y"], report["z"], tuple(report["joints"])


@pytest.mark.realtime
def test_a_double_clicked_stop_still_waits_for_the_arm_to_come_to_rest(tmp_path):
    """The run panel's Stop pressed twice (or two clients' stops): the job ended "interrupted"
    0.15-0.21 s after (4 of 4 runs) with ``last_line_executed`` None and ``resume_line`` 1, while
    the arm went on to run line 1 (its report moved from Z 300 to Z 150 over the next 1.4 s)
    and a new job was accepted meanwhile.  One stop: the job ends 1.2 s after, line 1 proven."""
    with served("--arm", f"a={SLOW}", journal=tmp_path) as server:
        status, created = server.request("POST", "/api/arms/a/jobs?name=long.txt", long_job(6))
        assert status == 201, created
        job_id = created["id"]
        _wait_frames(server, job_id, 1)
        for _ in range(2):  # (the second once the abort has begun: the first's own turn is done)
            status, answer = server.request("POST", f"/api/arms/a/jobs/{job_id}/stop")
            assert status == 200 and answer["stopping"] is True, answer
            time.sleep(0.1)
        job = server.wait_job("a", job_id)
        first = _pose(server)
        time.sleep(0.6)
        assert _pose(server) == first, "the job was shown ended while the arm still moved"
        assert job["outcome"] == "interrupted", job
        assert job["last_line_executed"] is not None and job["last_line_executed"] == job["last_line_sent"], job


@pytest.mark.realtime
def test_a_page_open_when_the_server_stops_is_told_the_job_ended_interrupted(tmp_path):
    """SIGINT mid-job with a page's WebSocket open: the job was stopped and the sockets closed
    (1001) at once, its ``summary`` published afterwards to nobody — the page's job line stayed
    at its last progress ("4/41 frames, last line executed 2"), no outcome, for good (3 of 3
    runs).  The docs' order holds now: the job stops (the arm waited for), its end reaches the
    viewers, then the sockets close."""
    async def watch(url: str, events: list) -> None:
        async with aiohttp.ClientSession() as session:
            async with session.ws_connect(url) as socket:
                async for message in socket:
                    if message.type == aiohttp.WSMsgType.TEXT:
                        events.append(json.loads(message.data))
                events.append({"event": "closed", "code": socket.close_code})

    async def main(server) -> tuple[dict, list]:
        events: list = []
        viewer = asyncio.ensure_future(watch(server.base.replace("http", "ws") + "/api/arms/a/events", events))
        while not events:
            await asyncio.sleep(0.02)
        status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/a/jobs?name=long.txt", long_job(40))
        assert status == 201, created
        await asyncio.to_thread(_wait_frames, server, created["id"], 3)
        server.process.send_signal(signal.SIGINT)
        await asyncio.wait_for(viewer, 30)
        assert await asyncio.to_thread(server.process.wait, 30) == 130
        return created, events

    with served("--arm", f"a={SLOW}", journal=tmp_path) as server:
        created, events = asyncio.run(main(server))
    assert events[-1] == {"event": "closed", "code": 1001}, events[-3:]
    summaries = [e for e in events if e["event"] == "summary"]
    assert [s["job"] for s in summaries] == [created["id"]], [e["event"] for e in events]
    assert summaries[0]["outcome"] == "interrupted", summaries[0]
    assert summaries[0]["last_line_executed"] == summaries[0]["last_line_sent"], summaries[0]  # the arm waited for


@pytest.mark.realtime
def test_closing_an_arm_whose_job_is_stopping_waits_for_the_arm(tmp_path):
    """A job stopped (from the API, or by the shutdown itself), then the arm closed while it
    stops — ``armctl serve``'s shutdown closes each arm after the sockets — and
    ``ArmService.close`` stopped the still-running job a second time: once the abort had begun
    (a page slow to answer the close frame gives it 1 s) the arm was no longer waited for.  Held
    here exactly: close once the abort sequence is in the journal."""
    from armctl.aio import AsyncArm
    from armctl.script.files import ScriptSnapshot
    from armctl.server.arms import ArmService

    async def main() -> dict:
        service = ArmService("a", SLOW, await AsyncArm.open(SLOW), tmp_path / "a")
        job, _ = await service.start_job(ScriptSnapshot("long.txt", long_job(6).encode()), None)

        async def journalled(text: str) -> None:
            deadline = time.monotonic() + 20
            while not job.log_path.exists() or text not in job.log_path.read_text():
                assert time.monotonic() < deadline, f"no {text} in the journal"
                await asyncio.sleep(0.01)

        await journalled('"line": 1')  # the first frame went
        assert await service.stop(None) is True
        await journalled('"abort": true')
        await service.close()
        return job.result

    result = asyncio.run(main())
    assert result["outcome"] == "interrupted" and result["last_line_sent"] is not None, result
    assert result["last_line_executed"] == result["last_line_sent"], result


@pytest.mark.realtime
def _interrupt_a_long_job(server) -> tuple[dict, float]:
    """A long job on arm ``a``, three frames in, then SIGINT to the server: the job as created,
    and when the signal was sent."""
    status, created = server.request("POST", "/api/arms/a/jobs?name=long.txt", long_job(40))
    assert status == 201, created
    _wait_frames(server, created["id"], 3)
    started = time.monotonic()
    server.process.send_signal(signal.SIGINT)
    return created, started


def test_a_second_ctrl_c_cuts_short_the_wait_for_the_arm_as_armctl_run_s_does(tmp_path):
    """docs/server.md: Ctrl-C stops a job as ``armctl run``'s does — whose second Ctrl-C stops
    waiting for the arm to come to rest.  ``armctl serve``'s handler only set its stop event,
    already set: a second SIGINT 0.5 s after the first changed nothing, the server exited 5.3 s
    after the first (sim://?speed=1: the 2 s lead of motion and the rest)."""
    with served("--arm", "a=sim://?speed=1", journal=tmp_path) as server:
        created, started = _interrupt_a_long_job(server)
        time.sleep(0.5)
        server.process.send_signal(signal.SIGINT)
        assert server.process.wait(40) == 130
        took_s = time.monotonic() - started
    assert took_s < 2.5, took_s
    records = [json.loads(line) for line in Path(created["journal"]).read_text().splitlines()]
    assert any(r["dir"] == "tx" and r.get("abort") for r in records), "no abort sequence in the journal"
    assert "Traceback" not in "".join(server.stderr_lines)


DEEP = "[" * 30000 + "]" * 30000  # JSON, nested deeper than Python's json parser recurses


@pytest.fixture(scope="module")
def fast_server(tmp_path_factory):
    with served("--arm", "a=sim://?speed=20", journal=tmp_path_factory.mktemp("journal")) as running:
        yield running


@pytest.mark.parametrize("body", [DEEP, '{"percent": ' + DEEP + "}"])
def test_a_body_nested_too_deep_for_the_parser_is_bad_json(fast_server, body):
    status, answer = fast_server.request("POST", "/api/arms/a/move", body, {"Content-Type": "application/json"})
    assert status == 400 and answer["code"] == "bad_json", answer
    assert "nested too deeply" in answer["error"], answer
    assert "Traceback" not in "".join(fast_server.stderr_lines)


def test_a_websocket_message_nested_too_deep_is_answered_with_an_error(fast_server):
    """docs/server.md: a message that is not JSON is answered with an ``error`` event."""
    async def main() -> list:
        async with aiohttp.ClientSession() as session:
            async with session.ws_connect(fast_server.base.replace("http", "ws") + "/api/arms/a/events") as socket:
                assert (await socket.receive_json(timeout=10))["event"] == "hello"
                await socket.send_str(DEEP)
                await socket.send_json({"ping": 7})
                answers = []
                while not answers or answers[-1].get("event") != "pong":
                    message = await socket.receive(timeout=10)
                    assert message.type == aiohttp.WSMsgType.TEXT, (message.type, message.data, socket.close_code)
                    if json.loads(message.data)["event"] != "status":
                        answers.append(json.loads(message.data))
                return answers

    answers = asyncio.run(main())
    assert [a["event"] for a in answers] == ["error", "pong"], answers
    assert "Traceback" not in "".join(fast_server.stderr_lines)


@pytest.mark.realtime
def test_resume_while_a_job_stops_is_refused_and_the_arm_stays_at_rest(tmp_path):
    """On an arm whose control frames act as they land (``control_frames=arrival``) the stop's
    pause freezes the arm mid-move and the queue is cleared.  A Resume pressed then (the run
    panel's, after its Stop) was answered ``toggle_sent: true``: not carried out by the stopping
    job, it was sent to the idle arm after the job ended "interrupted", last line executed None,
    resume line 1 — and the arm went on to finish line 1 (Z 283 → 192 → 150 over the next
    second).  A job that is stopping takes no pause, resume or feed: 409, as a job that ended."""
    with served("--arm", "a=sim://?speed=4&control_frames=arrival", journal=tmp_path) as server:
        status, created = server.request("POST", "/api/arms/a/jobs?name=long.txt", long_job(10))
        assert status == 201, created
        job_id = created["id"]
        _wait_frames(server, job_id, 3)
        assert server.request("POST", f"/api/arms/a/jobs/{job_id}/stop")[0] == 200
        status, answer = server.request("POST", f"/api/arms/a/jobs/{job_id}/resume")
        assert status == 409 and answer["code"] == "busy" and "stopping" in answer["error"], answer
        job = server.wait_job("a", job_id)
        assert job["outcome"] == "interrupted", job
        first = _pose(server)
        time.sleep(0.6)
        assert _pose(server) == first, "the arm moved after its job was shown interrupted"


@pytest.mark.realtime
def test_a_stopping_server_takes_no_new_job_or_move(tmp_path):
    """A stopping server waits for each stopped job's arm (its summary before the sockets
    close); meanwhile it still answered requests, and a move asked of the other, idle arm 0.3 s
    after SIGINT was started and waited for: the server exited after the move's 37 s.  Now every
    POST is refused once the server stops: 503 ``stopping``."""
    with served("--arm", "a=sim://?speed=1", "--arm", "b=sim://?speed=1", journal=tmp_path) as server:
        created, started = _interrupt_a_long_job(server)
        time.sleep(0.3)
        status, answer = server.request("POST", "/api/arms/b/move",
                                        {"x": 250, "y": 100, "z": 150, "a": 180, "b": 0, "c": 0, "f": 300}, timeout=60)
        assert status == 503 and answer["code"] == "stopping", answer
        assert server.process.wait(40) == 130
        assert time.monotonic() - started < 15
