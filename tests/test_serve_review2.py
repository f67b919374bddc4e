"""``armctl serve``'s faults the second server review found (wt-serve2): each test failed
before its fix.

A listen address in use is refused before any arm's port is opened (the installed command, a
pseudo-terminal standing in for the arm's serial port: its settings and its input show whether
armctl opened it or wrote to it).  A port lost under a running server is the server's
condition, answered 503 ``port_lost`` with the way back, not a 422 for the client's request
(the installed command, the simulator behind a TCP bridge that the test stops).  Uploads
waiting for their check are bounded: their bytes held at once, beyond which the server
answers 503 at once instead of queueing minutes of checking and their bodies' memory.  The
viewers' limit is checked and taken in one step: connects arriving together cannot pass it.
"""
from __future__ import annotations

import asyncio
import os
import queue
import socket
import subprocess
import sys
import threading
import time

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import ARMCTL, served  # noqa: E402
from test_serve_review import moves, with_client  # noqa: E402

pytestmark = pytest.mark.timeout(60)


@pytest.mark.skipif(sys.platform == "win32", reason="a pseudo-terminal stands in for the arm's serial port")
def test_a_listen_address_in_use_is_refused_before_any_arm_is_opened(tmp_path):
    """The arms were opened first (a real arm's serial port configured, its link started) and
    only then was the address found taken: a user was told the server cannot start after
    armctl had taken their arm.  Now nothing touches the arm: exit 2, one line saying so."""
    import select
    import termios

    master, arm_side = os.openpty()
    try:
        settings = termios.tcgetattr(arm_side)
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen()
            port = taken.getsockname()[1]
            result = subprocess.run([str(ARMCTL), "serve", "--arm", f"a={os.ttyname(arm_side)}", "--arm", "b=sim://",
                                     "--listen", f"127.0.0.1:{port}", "--journal-dir", str(tmp_path)],
                                    capture_output=True, text=True, timeout=30)
        assert result.returncode == 2, result.stderr
        assert result.stdout == ""
        lines = result.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"armctl: cannot listen on 127.0.0.1:{port}: "), result.stderr
        assert "already in use" in lines[0].lower()
        assert termios.tcgetattr(arm_side) == settings, "the arm's port was opened (its line settings changed)"
        assert not select.select([master], [], [], 0)[0], "bytes were written to the arm"
    finally:
        os.close(master)
        os.close(arm_side)


@pytest.mark.realtime  # the simulator behind a bridge, in real time
def test_a_lost_port_is_answered_503_port_lost_with_the_way_back(tmp_path):
    """A status read after the arm's port went away (the cable pulled) was 422 'refused', as if
    the client had asked for something wrong; it is the arm's condition: 503, its own code,
    saying what was lost and how to come back."""
    from armctl.sim.bridge import serve_tcp
    from armctl.sim.model import SimOptions

    ready: queue.Queue = queue.Queue()
    pulled = threading.Event()
    bridge = threading.Thread(target=serve_tcp, args=(0, SimOptions(), ready.put, pulled, 1.0), daemon=True)
    bridge.start()
    url = ready.get(timeout=10)
    try:
        with served("--arm", f"a={url}", journal=tmp_path) as server:
            assert server.request("GET", "/api/arms/a/status")[0] == 200
            pulled.set()
            bridge.join(10)
            deadline = time.monotonic() + 10
            while (answer := server.request("GET", "/api/arms/a/status"))[0] == 200 and time.monotonic() < deadline:
                time.sleep(0.05)
            status, body = answer
            assert (status, body["code"]) == (503, "port_lost"), answer
            assert f"the port {url} went away" in body["error"] and "restart armctl serve" in body["error"], body
    finally:
        pulled.set()
        bridge.join(10)


def test_uploads_waiting_for_their_check_are_bounded_and_the_rest_refused_at_once(tmp_path, monkeypatch):
    """Script checks run one at a time; every upload waited its turn holding its body, so a
    neighbour posting scripts kept a core busy for as long as they liked (a 128 MiB one is about
    a minute of checking) and the server's memory grew by each body.  The bytes held at once
    (read, waiting, being checked) are bounded: beyond, 503 ``too_busy`` at once, and the
    uploads held are answered as before once the checks run."""
    from armctl.server import app, arms

    script = moves(6_000).encode()  # 130 kB: two fit under the bound set here, three do not
    monkeypatch.setattr(app, "SCRIPTS_HELD_BYTES", 2 * len(script) + 1000, raising=False)

    async def test(client, services):
        arms._SCRIPT_WORK.acquire()  # the checker busy with a neighbour's script
        try:
            held = [asyncio.ensure_future(client.post("/api/arms/a/lint", data=script)) for _ in range(2)]
            await asyncio.sleep(0.5)
            refused = await asyncio.wait_for(client.post("/api/arms/a/lint", data=script), 10)
            answer = await refused.json()
            assert (refused.status, answer["code"]) == (503, "too_busy"), answer
            assert not any(upload.done() for upload in held)
        finally:
            arms._SCRIPT_WORK.release()
        for upload in held:
            response = await asyncio.wait_for(upload, 30)
            assert response.status == 200 and (await response.json())["errors"] == 0
        again = await client.post("/api/arms/a/lint", data=script)
        assert again.status == 200, "the bytes of the uploads answered are still counted"

    with_client(tmp_path, test)


def test_connects_arriving_together_cannot_pass_the_viewer_limit(tmp_path, monkeypatch):
    """The limit was checked when a WebSocket connected and the viewer counted only after its
    handshake and hello were written: every connect whose handshake waited (a slow client, a
    response hook; here a hook that yields once) passed the check together.  40 connects at once
    against a limit of 5: 5 viewers, the rest 503 ``too_many_viewers``."""
    from armctl.server import app as server_app

    monkeypatch.setattr(server_app, "MAX_VIEWERS", 5)

    async def main():
        from aiohttp import WSServerHandshakeError
        from aiohttp.test_utils import TestClient, TestServer

        from armctl.aio import AsyncArm
        from armctl.server.arms import ArmService

        service = ArmService("a", "sim://?clock=virtual", await AsyncArm.open("sim://?clock=virtual"), tmp_path / "a")
        application = server_app.build_app({"a": service}, token=None, host="127.0.0.1")

        async def handshake_waits(request, response) -> None:
            await asyncio.sleep(0.01)

        application.on_response_prepare.append(handshake_waits)
        client = TestClient(TestServer(application))
        await client.start_server()

        async def connect():
            try:
                socket = await client.ws_connect("/api/arms/a/events")
            except WSServerHandshakeError as error:
                return error.status
            assert (await socket.receive_json())["event"] == "hello"
            return socket

        try:
            answers = await asyncio.wait_for(asyncio.gather(*(connect() for _ in range(40))), 30)
            sockets = [answer for answer in answers if not isinstance(answer, int)]
            assert len(sockets) == 5 and len(service.hub.viewers) == 5, (len(sockets), len(service.hub.viewers))
            assert sorted(set(answers) - set(sockets)) == [503]
            for socket in sockets:
                await socket.close()
        finally:
            await client.close()
            await service.close()

    asyncio.run(main())


def test_the_controlling_socket_is_not_told_that_another_client_controls(tmp_path):
    """(The viewer now counts from before its hello: the control event its own connect publishes
    for the others must not reach it.)"""

    async def test(client, services):
        socket = await client.ws_connect("/api/arms/a/events?control=1&client=me")
        assert (await socket.receive_json())["control"] is True
        await socket.send_json({"ping": 1})
        assert (await asyncio.wait_for(socket.receive_json(), 10))["event"] == "pong"
        await socket.close()

    with_client(tmp_path, test)
