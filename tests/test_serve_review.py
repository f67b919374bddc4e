"""``armctl serve`` broken as users and careless neighbours break it (the wt-serve review):
each test is a fault the review found, and failed before its fix.

In-process (aiohttp's test client over virtual-clock arms): a big upload does not freeze the
event loop (the jog dead-man, the events, every other request live on it); status reads on a
virtual-clock arm during a job do not take the threads a pause needs; a body that is not
UTF-8 is bad JSON (400); one client's two sockets (a duplicated tab) keep control until the
last closes.  One fresh process: SIGHUP (the terminal closed) mid-job stops the job as Ctrl-C
does, and SIGTERM with a page open exits at once, not after aiohttp's 15 s wait.
"""
from __future__ import annotations

import asyncio
import json
import signal
import time
from pathlib import Path

import pytest

aiohttp = pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from aiohttp.test_utils import TestClient, TestServer  # noqa: E402

from armctl.aio import AsyncArm  # noqa: E402
from armctl.server.app import build_app  # noqa: E402
from armctl.server.arms import ArmService  # noqa: E402
from serve_process import served  # noqa: E402

pytestmark = pytest.mark.timeout(90)

VIRTUAL = "sim://?clock=virtual"
FIRST = "G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000"


def moves(count: int) -> str:
    """A valid script of ``count`` short moves after the first line."""
    return "\n".join([FIRST] + [f"G1 X{220 + i % 40} Y{i % 30}" for i in range(count)]) + "\n"


def with_client(tmp_path, test, arms=("a",)):
    async def main():
        services = {name: ArmService(name, VIRTUAL, await AsyncArm.open(VIRTUAL), tmp_path / name) for name in arms}
        client = TestClient(TestServer(build_app(services, token=None, host="127.0.0.1")))
        await client.start_server()
        try:
            await test(client, services)
        finally:
            for service in services.values():
                await service.arm.stop("the test ended")
            await client.close()
            for service in services.values():
                await service.close()

    asyncio.run(main())


@pytest.mark.parametrize("path", ["/api/arms/a/lint", "/api/arms/a/preview", "/api/arms/a/jobs"])
def test_a_big_script_being_checked_does_not_freeze_the_server(tmp_path, path):
    """A neighbour's 3.5 MB script (its check takes seconds, a 128 MiB one a minute) was checked
    on the event loop: every WebSocket, the status events and the jog dead-man (its neutral is
    due 75 ms after the last heartbeat) waited for it.  The server (here the test's own
    loop too) keeps answering pings while the check runs: no round takes a third of its time."""
    big = moves(300_000) + "G1 Z\n"  # an error on the last line: every path checks the whole script

    async def test(client, services):
        socket = await client.ws_connect("/api/arms/a/events")
        assert (await socket.receive_json())["event"] == "hello"
        sent = time.monotonic()
        upload = asyncio.ensure_future(client.post(path, data=big))
        slowest_s = 0.0  # the longest round: a ping answered, then 20 ms of sleep (the loop's lag)
        while not upload.done():
            pinged = time.monotonic()
            await socket.send_json({"ping": 1})
            while (await asyncio.wait_for(socket.receive_json(), 60))["event"] != "pong":
                pass
            await asyncio.sleep(0.02)
            slowest_s = max(slowest_s, time.monotonic() - pinged)
        response = await upload
        checked_s = time.monotonic() - sent
        assert response.status in (200, 422)
        assert (await response.json())["diagnostics"][-1]["line"] == 300_002
        assert checked_s > 0.8, "the check was too quick to show anything"
        assert slowest_s < checked_s / 3, (slowest_s, checked_s)
        await socket.close()

    with_client(tmp_path, test)


def test_status_reads_on_a_virtual_arm_during_a_job_do_not_hold_up_a_pause(tmp_path):
    """On a virtual-clock arm a status read waits for the running job (model time moves only
    there).  Four of them took every thread of the arm's pool: a pause waited for the job's end
    (25 s for a 100,000-line job), then paused the idle arm — the job 'finished', the arm left
    paused.  The pause must be answered while the job runs."""

    async def test(client, services):
        created = await (await client.post("/api/arms/a/jobs?name=long.txt", data=moves(40_000))).json()
        job = services["a"].jobs[created["id"]]
        await asyncio.wait_for(job.streaming.wait(), 30)
        reads = [asyncio.ensure_future(client.get("/api/arms/a/status")) for _ in range(4)]
        await asyncio.sleep(0.3)
        response = await asyncio.wait_for(client.post(f"/api/arms/a/jobs/{job.id}/pause"), 60)
        assert response.status == 200, await response.json()
        assert services["a"].running is job, "the pause was answered only after the job ended"
        await services["a"].arm.stop("the test is done")
        for read in reads:
            assert (await asyncio.wait_for(read, 60)).status == 200
        assert (await (await client.get(f"/api/arms/a/jobs/{job.id}")).json())["outcome"] == "interrupted"

    with_client(tmp_path, test)


@pytest.mark.parametrize("endpoint", ["move", "jobs/{id}/feed"])
def test_a_body_that_is_not_utf8_is_bad_json(tmp_path, endpoint):
    """Bytes that are not UTF-8 where JSON is expected were 422 'refused' with Python's codec
    message ("'utf-8' codec can't decode byte 0xb0 in position 2: …")."""

    async def test(client, services):
        job_id = "none"
        if "{id}" in endpoint:
            job_id = (await (await client.post("/api/arms/a/jobs", data=moves(40_000))).json())["id"]
        response = await client.post(f"/api/arms/a/{endpoint.format(id=job_id)}", data=b'{"x": "\xb0\xff"}')
        answer = await response.json()
        assert (response.status, answer["code"]) == (400, "bad_json"), answer
        assert "UTF-8" in answer["error"] and "codec" not in answer["error"]

    with_client(tmp_path, test)


def test_a_duplicated_tab_keeps_control_until_its_last_socket_closes(tmp_path):
    """A duplicated browser tab copies sessionStorage, so both tabs are the same client and both
    were told they control the arm; the first to close released control while the other still
    showed 'in control' — and a third tab then took it.  Control is held until the controlling
    client's last WebSocket closes."""

    async def test(client, services):
        first = await client.ws_connect("/api/arms/a/events?control=1&client=tab")
        second = await client.ws_connect("/api/arms/a/events?control=1&client=tab")
        assert (await first.receive_json())["control"] is True
        assert (await second.receive_json())["control"] is True
        await first.close()
        await asyncio.sleep(0.1)
        assert services["a"].controller == "tab"
        third = await client.ws_connect("/api/arms/a/events?control=1&client=other")
        assert (await third.receive_json())["control"] is False
        await second.close()
        await asyncio.sleep(0.1)
        assert services["a"].controller is None
        await third.close()

    with_client(tmp_path, test)


@pytest.mark.realtime
@pytest.mark.parametrize("signal_name", ["SIGHUP", "SIGTERM"])
def test_a_signal_mid_job_with_a_page_open_stops_the_job_and_exits_130_promptly(tmp_path, signal_name):
    """The installed command: a job running, a page's WebSocket open, then SIGHUP (the terminal
    closed) or SIGTERM.  SIGHUP ended the process in 0.1 s with no abort sequence (the journal
    stops after the last frame written, the arm left running its queue); SIGTERM did stop the
    job but exited only after 15.5 s, aiohttp waiting for the open WebSocket."""
    from test_server_api import long_job

    async def main(server):
        async with aiohttp.ClientSession() as session:
            page = await session.ws_connect(server.base.replace("http", "ws") + "/api/arms/a/events?control=1&client=page")
            assert (await page.receive_json())["event"] == "hello"
            status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/a/jobs?name=long.txt",
                                                      long_job(40), {"X-Armctl-Client": "page"})
            assert status == 201, created
            deadline = time.monotonic() + 20
            while (await asyncio.to_thread(server.request, "GET", f"/api/arms/a/jobs/{created['id']}"))[1]["frames_sent"] < 3:
                assert time.monotonic() < deadline
                await asyncio.sleep(0.05)
            started = time.monotonic()
            server.process.send_signal(getattr(signal, signal_name))
            code = await asyncio.to_thread(server.process.wait, 40)
            return created, code, time.monotonic() - started

    with served("--arm", "a=sim://?speed=4", journal=tmp_path) as server:
        created, code, took_s = asyncio.run(main(server))
    assert code == 130
    assert took_s < 8, took_s  # the arm's queued motion (the 2 s lead) and the abort, not 15 s more
    records = [json.loads(line) for line in Path(created["journal"]).read_text().splitlines()]
    assert any(r["dir"] == "tx" and r.get("abort") for r in records), "no abort sequence in the journal"
    assert "Traceback" not in "".join(server.stderr_lines)


def test_big_scripts_sent_at_once_are_checked_one_at_a_time(tmp_path, monkeypatch):
    """Checks run off the event loop, but two at once starve the arm's worker thread of the GIL:
    three 12 MB lints at once made a 48.3 s job (sim://?speed=4) take 49.4 s and 85.1 s of arm
    time (one at a time: 48.3 s and 48.5 s).  Scripts sent together are checked one at a time."""
    import threading

    import armctl.core.checked as checked

    inside, most = [0], [0]
    lock = threading.Lock()
    real_check = checked.check

    def counted(*args, **kwargs):
        with lock:
            inside[0] += 1
            most[0] = max(most[0], inside[0])
        try:
            time.sleep(0.2)  # a big script's check, long enough to overlap
            return real_check(*args, **kwargs)
        finally:
            with lock:
                inside[0] -= 1

    monkeypatch.setattr(checked, "check", counted)

    async def test(client, services):
        answers = await asyncio.gather(*(client.post(path, data=moves(10) + "G1 Z\n") for path in
                                         ("/api/arms/a/lint", "/api/arms/a/preview", "/api/arms/b/jobs", "/api/arms/b/lint")))
        assert sorted(answer.status for answer in answers) == [200, 200, 422, 422]
        assert most[0] == 1, f"{most[0]} checks ran at once"

    with_client(tmp_path, test, arms=("a", "b"))


def test_a_binary_websocket_message_is_answered_with_an_error(tmp_path):
    """docs/server.md: any message that is not a JSON object with "jog" or "ping" is answered
    with an error event (a client waiting for an answer is never left waiting); a binary one
    was dropped without a word."""

    async def test(client, services):
        socket = await client.ws_connect("/api/arms/a/events")
        assert (await socket.receive_json())["event"] == "hello"
        await socket.send_bytes(b'{"ping": 1}')
        while True:
            event = await asyncio.wait_for(socket.receive_json(), 5)
            if event["event"] != "status":
                break
        assert event["event"] == "error" and "text" in event["error"], event
        await socket.close()

    with_client(tmp_path, test)


@pytest.mark.realtime
@pytest.mark.timeout(120)
def test_a_read_only_page_takes_control_when_the_controlling_page_closes(tmp_path):
    """In chromium: the first page controls the arm, a second is read-only.  When the first
    closed, the server freed the arm (any client may drive it) but the second page went on
    saying 'read-only' — and could in fact run jobs — until reloaded.  It takes control."""
    from test_server_browser import By, headless_chromium, wait  # (skips this test where no browser is)

    def badge(driver, expected: str) -> None:
        wait(driver, lambda d: d.find_element(By.CSS_SELECTOR, 'section[data-arm="a"] .badge').text == expected)

    with headless_chromium() as driver, served("--arm", "a=sim://?speed=20", journal=tmp_path) as server:
        driver.get(server.base + "/")
        badge(driver, "in control")
        first = driver.current_window_handle
        driver.switch_to.new_window("tab")  # a page of its own (its own sessionStorage: another client)
        driver.get(server.base + "/")
        badge(driver, "read-only")
        second = driver.current_window_handle
        driver.switch_to.window(first)
        driver.close()
        driver.switch_to.window(second)
        badge(driver, "in control")
        assert server.request("GET", "/api/arms")[1][0]["controlled"] is True


@pytest.mark.realtime
def test_ctrl_c_while_big_scripts_are_being_checked_exits_at_once(tmp_path):
    """The installed command, three 4.7 MB scripts sent to lint at once, then SIGINT: the server
    waited for every check (each seconds of CPU; with three 12 MB ones it exited after 31.5 s,
    77 s when they ran on the event loop).  A check has no effect to wait for: it is abandoned."""
    import threading
    import urllib.request

    big = moves(400_000).encode()
    with served("--arm", "a=sim://?speed=20", journal=tmp_path) as server:
        def lint() -> None:
            try:
                urllib.request.urlopen(urllib.request.Request(server.base + "/api/arms/a/lint", data=big, method="POST"),
                                       timeout=60).read()
            except OSError:
                pass  # the server stopped first

        clients = [threading.Thread(target=lint, daemon=True) for _ in range(3)]
        for client in clients:
            client.start()
        time.sleep(1.0)  # the bodies are in, the first check under way
        started = time.monotonic()
        server.process.send_signal(signal.SIGINT)
        assert server.process.wait(60) == 130
        took_s = time.monotonic() - started
    assert took_s < 2.5, took_s  # the checks queued take 3 x 2.5 s or more
    assert "Traceback" not in "".join(server.stderr_lines)


def test_a_plain_get_of_the_websocket_path_is_a_json_error(tmp_path):
    """Every error is {"error", "code"} with a 4xx status (docs/server.md): a GET of the events
    path without the WebSocket upgrade (a browser's address bar, curl) was 400 in plain text
    ('No WebSocket UPGRADE hdr: None …')."""

    async def test(client, services):
        response = await client.get("/api/arms/a/events")
        assert response.status == 400
        answer = await response.json(content_type=None)
        assert answer["code"] == "bad_request" and "WebSocket" in answer["error"], answer

    with_client(tmp_path, test)


def test_a_client_gone_before_its_hello_leaves_the_arm_uncontrolled(tmp_path, monkeypatch):
    """A WebSocket that asks for control and is gone before its hello is written (a reload at
    the wrong instant; 200 connections reset just after their upgrade request did it in a
    fresh process) left the arm controlled by nobody there: every state-changing request of
    every client was 409 read_only until the server restarted.  Here the hello's write fails."""
    from aiohttp import web

    real_send_json = web.WebSocketResponse.send_json

    async def send_json(self, data, *args, **kwargs):
        if isinstance(data, dict) and data.get("event") == "hello":
            raise ConnectionResetError("Cannot write to closing transport")
        return await real_send_json(self, data, *args, **kwargs)

    monkeypatch.setattr(web.WebSocketResponse, "send_json", send_json)

    async def test(client, services):
        socket = await client.ws_connect("/api/arms/a/events?control=1&client=gone")
        await socket.receive()  # the server ends it
        await socket.close()
        await asyncio.sleep(0.1)
        assert services["a"].controller is None
        assert not services["a"].hub.viewers
        response = await client.post("/api/arms/a/jobs", data=FIRST + "\n", headers={"X-Armctl-Client": "another"})
        assert response.status == 201, await response.json()  # not 409 read_only

    with_client(tmp_path, test)
