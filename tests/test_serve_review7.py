"""Review of ``armctl serve`` as its users meet it: a refused resume in the server's words, jog
messages during the shutdown wait, a ``dropped`` event on the page.  The installed command on a
free loopback port (tests/serve_process.py)."""
from __future__ import annotations

import asyncio
import json
import signal
import time

import pytest

aiohttp = pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import served  # noqa: E402
from test_server_api import long_job  # noqa: E402

pytestmark = pytest.mark.timeout(60)

VIRTUAL = "sim://?clock=virtual"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z120\nG1 Z100\n"
CLI_WORDS = ("--resume", "--port", "--from-line", "--other-port")


def test_a_refused_resume_speaks_the_server_words(tmp_path):
    """A job of a server that has stopped since, on its simulated arm (gone with its process),
    resumed by the next server: refused (422, nothing sent) naming the job the request named and
    the server's ways out, not ``armctl run``'s flags."""
    with served("--arm", f"a={VIRTUAL}", journal=tmp_path) as server:
        status, created = server.request("POST", "/api/arms/a/jobs?name=job.txt", JOB)
        assert status == 201, created
        assert server.wait_job("a", created["id"])["outcome"] == "finished"
    with served("--arm", f"a={VIRTUAL}", journal=tmp_path) as server:
        status, refused = server.request("POST", f"/api/arms/a/jobs?resume={created['id']}")
    assert status == 422 and refused["code"] == "refused", refused
    message = refused["error"]
    assert "does not outlive its process" in message, message
    assert f"?resume={created['id']}" in message and "POST /api/arms/a/jobs" in message, message
    assert not any(flag in message for flag in CLI_WORDS), message


@pytest.mark.realtime
def test_no_jog_moves_an_arm_while_the_server_shuts_down(tmp_path):
    """SIGINT while arm ``a``'s job runs: the server waits for that job to stop (the arm to come to
    rest), its WebSockets still open.  A jog on arm ``b``, idle, from the page controlling it, was
    carried out meanwhile (its joystick frames went, a ``jog`` event) — only the dead-man's lease
    capped it.  Nothing may move an arm while the server shuts down: refused (an ``error`` event)."""
    async def main(server) -> list:
        ws = server.base.replace("http://", "ws://") + "/api/arms/b/events?control=1&client=page"
        async with aiohttp.ClientSession() as session, session.ws_connect(ws) as page:
            hello = await page.receive_json(timeout=10)
            assert hello["event"] == "hello" and hello["control"] is True, hello
            status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/a/jobs?name=long.txt",
                                                      long_job(40))
            assert status == 201, created
            while (await asyncio.to_thread(server.request, "GET", f"/api/arms/a/jobs/{created['id']}"))[1][
                    "frames_sent"] < 3:
                await asyncio.sleep(0.02)
            server.process.send_signal(signal.SIGINT)
            deadline = time.monotonic() + 10
            while (await asyncio.to_thread(server.request, "POST", "/api/arms/b/stop"))[0] != 503:  # stopping now
                assert time.monotonic() < deadline, "the server did not begin to stop"
                await asyncio.sleep(0.02)
            answers = []
            for _ in range(10):  # a held button's heartbeats, for 0.3 s
                await page.send_json({"jog": "j1_plus"})
                await asyncio.sleep(0.03)
            await page.send_json({"jog": None})
            async for message in page:
                if message.type == aiohttp.WSMsgType.TEXT and json.loads(message.data)["event"] in ("jog", "error"):
                    answers.append(json.loads(message.data))
            return answers

    with served("--arm", "a=sim://?speed=1", "--arm", "b=sim://", journal=tmp_path) as server:
        answers = asyncio.run(main(server))
        assert server.process.wait(30) == 130
    moved = [a for a in answers if a["event"] == "jog" and any(frame != [128] for frame in a["frames"])]
    assert moved == [], moved
    refused = [a for a in answers if a["event"] == "error"]
    assert refused and all("stopping" in a["error"] for a in refused), answers
