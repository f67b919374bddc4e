"""``armctl serve``'s WebSocket, control and security, as clients reach them: the installed
command in a subprocess, an aiohttp WebSocket client; and the event hub's bound in-process."""
from __future__ import annotations

import asyncio
import json
import os
import stat
import time
from pathlib import Path

import pytest

aiohttp = pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import flood_a_slow_viewer, served  # noqa: E402

pytestmark = [pytest.mark.realtime, pytest.mark.timeout(90)]

SHORT = (Path(__file__).parent / "data" / "scripts_cli" / "short_job.txt").read_text()
FAST = "sim://?speed=20"


def ws_url(server, arm: str, **query) -> str:
    text = "&".join(f"{k}={v}" for k, v in query.items())
    return server.base.replace("http://", "ws://") + f"/api/arms/{arm}/events" + (f"?{text}" if text else "")


async def receive_until(socket, predicate, timeout_s: float = 30.0) -> list[dict]:
    events = []
    async with asyncio.timeout(timeout_s):
        while True:
            message = await socket.receive()
            assert message.type == aiohttp.WSMsgType.TEXT, message
            event = json.loads(message.data)
            events.append(event)
            if predicate(event):
                return events


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with served("--arm", f"a={FAST}", "--arm", f"b={FAST}", journal=tmp_path_factory.mktemp("journal")) as running:
        yield running


def test_events_are_the_run_json_events_and_status_updates(server):
    async def main():
        async with aiohttp.ClientSession() as session, session.ws_connect(ws_url(server, "a")) as socket:
            hello = await receive_until(socket, lambda e: True)
            assert hello[0]["event"] == "hello" and hello[0]["control"] is False
            await receive_until(socket, lambda e: e["event"] == "status")
            status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/a/jobs", SHORT)
            assert status == 201
            events = await receive_until(socket, lambda e: e["event"] == "summary" and e.get("job") == created["id"])
            job_events = [e for e in events if e.get("job") == created["id"]]
            kinds = [e["event"] for e in job_events]
            assert kinds[0] == "job" and "started" in kinds and "progress" in kinds
            summary = job_events[-1]
            assert summary["outcome"] == "finished" and summary["frames_sent"] == summary["total_frames"] == 5
            started = next(e for e in job_events if e["event"] == "started")
            assert {"total_frames", "estimated_job_s", "lead_s"} <= set(started)
            progress = [e for e in job_events if e["event"] == "progress"]
            assert {"frames_sent", "last_line_executed", "eta_s", "pause_state", "feed_percent"} <= set(progress[-1])
            # status updates go on around the job (every STATUS_EVERY_S; a job may end sooner)
            after = await receive_until(socket, lambda e: e["event"] == "status")
            assert set(after[-1]["status"]) >= {"x", "y", "z", "joints", "paused"}

    asyncio.run(main())


def test_every_message_is_answered_an_unusable_one_with_an_error(server):
    # a JSON list, an object with neither "jog" nor "ping", or not JSON at all: each gets an error
    # event (a list and an unknown object were silently dropped), and a ping its pong
    async def main():
        async with aiohttp.ClientSession() as session, session.ws_connect(ws_url(server, "a")) as socket:
            await receive_until(socket, lambda e: e["event"] == "hello")
            for sent in ("[1, 2]", '{"jgo": "j1_plus"}', '"jog"', "{jog"):
                await socket.send_str(sent)
                answer = await receive_until(socket, lambda e: e["event"] in ("error", "pong"))
                assert answer[-1]["event"] == "error", (sent, answer[-1])
            await socket.send_str('{"ping": 7}')
            answer = await receive_until(socket, lambda e: e["event"] in ("error", "pong"))
            assert answer[-1]["event"] == "pong" and answer[-1]["ping"] == 7, answer[-1]

    asyncio.run(main())


def test_one_controlling_client_at_a_time_the_others_read_only(server):
    async def main():
        async with aiohttp.ClientSession() as session:
            first = await session.ws_connect(ws_url(server, "b", control=1, client="first"))
            hello = (await receive_until(first, lambda e: True))[0]
            assert hello["control"] is True and hello["client"] == "first"
            second = await session.ws_connect(ws_url(server, "b", control=1, client="second"))
            hello = (await receive_until(second, lambda e: True))[0]
            assert hello["control"] is False and hello["controlled"] is True
            status, answer = await asyncio.to_thread(server.request, "POST", "/api/arms/b/jobs", SHORT,
                                                     {"X-Armctl-Client": "second"})
            assert status == 409 and answer["code"] == "read_only"
            status, answer = await asyncio.to_thread(server.request, "POST", "/api/arms/b/move", {"z": 250, "f": 3000})
            assert status == 409 and answer["code"] == "read_only"  # no client id at all: read-only too
            status, created = await asyncio.to_thread(server.request, "POST", "/api/arms/b/jobs", SHORT,
                                                      {"X-Armctl-Client": "first"})
            assert status == 201
            await first.close()  # the controller goes away mid-job: the job goes on, control is free again
            job = await asyncio.to_thread(server.wait_job, "b", created["id"])
            assert job["outcome"] == "finished" and job["frames_sent"] == job["total_frames"]
            third = await session.ws_connect(ws_url(server, "b", control=1, client="third"))
            assert (await receive_until(third, lambda e: True))[0]["control"] is True
            await third.close()
            await second.close()

    asyncio.run(main())


def test_jog_gets_the_neutral_within_100_ms_of_a_lost_heartbeat_or_a_closed_socket(server):
    async def main():
        async with aiohttp.ClientSession() as session:
            watcher = await session.ws_connect(ws_url(server, "a"))
            await receive_until(watcher, lambda e: True)
            for ending in ("lost heartbeat", "closed"):
                jogger = await session.ws_connect(ws_url(server, "a", control=1, client="jogger"))
                assert (await receive_until(jogger, lambda e: True))[0]["control"] is True
                for _ in range(8):  # 200 ms of heartbeats, then silence (or the tab closes)
                    await jogger.send_json({"jog": "j1_plus"})
                    await asyncio.sleep(0.025)
                last_beat = time.monotonic()
                if ending == "closed":
                    await jogger.close()
                jogs = await receive_until(watcher, lambda e: e["event"] == "jog" and e["frames"] == [[128]], 5)
                stopped_after_s = time.monotonic() - last_beat
                assert any(e["event"] == "jog" and e["frames"][0] != [128] for e in jogs)  # it did move
                assert stopped_after_s < 0.100 + 0.05, (ending, stopped_after_s)  # + the event's own way to us
                if ending != "closed":
                    await jogger.close()
                await asyncio.sleep(0.1)
            await watcher.close()

    asyncio.run(main())


def test_a_slow_viewer_loses_events_and_holds_a_bounded_queue():
    """In-process: a viewer that never reads, 40,000 events of 1 kB published at it (40 MB):
    the server holds at most its queue (and the sockets' buffers), and counts what it dropped."""
    from armctl.server.hub import QUEUE_EVENTS

    flood = asyncio.run(flood_a_slow_viewer(40_000, 1000))
    assert flood["largest_queue"] <= QUEUE_EVENTS
    assert flood["dropped"] > 30_000  # it read (almost) nothing: most events were dropped for it
    assert flood["peak_growth_mb"] < 5  # against 40 MB published


def test_non_loopback_listen_refuses_requests_without_the_token(tmp_path):
    token = "s3cret-token-for-the-test-0123456789"
    token_file = tmp_path / "token"
    token_file.write_text(token + "\n")
    with served("--arm", f"a={FAST}", "--token-file", str(token_file), journal=tmp_path / "j",
                listen_host="0.0.0.0", connect_host="127.0.0.1") as server:
        assert token not in server.banner
        status, answer = server.request("GET", "/api/arms")
        assert status == 401 and answer["code"] == "unauthorized"
        status, answer = server.request("POST", "/api/arms/a/jobs", SHORT)
        assert status == 401
        status, _ = server.request("GET", "/api/arms", headers={"Authorization": "Bearer wrong-token-0123456789"})
        assert status == 401
        bearer = {"Authorization": f"Bearer {token}"}
        status, arms = server.request("GET", "/api/arms", headers=bearer)
        assert status == 200 and arms[0]["name"] == "a"
        status, created = server.request("POST", "/api/arms/a/jobs", SHORT, headers=bearer)
        assert status == 201
        assert server.wait_job("a", created["id"], headers=bearer)["outcome"] == "finished"
        status, page = server.request("GET", "/")  # the page holds no secret
        assert status == 200

        async def sockets():
            async with aiohttp.ClientSession() as session:
                with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                    await session.ws_connect(ws_url(server, "a"))
                assert refused.value.status == 401
                async with session.ws_connect(ws_url(server, "a"), headers=bearer) as socket:
                    assert (await receive_until(socket, lambda e: True))[0]["event"] == "hello"
                async with session.ws_connect(ws_url(server, "a"), protocols=("armctl", f"bearer.{token}")) as socket:
                    assert socket.protocol == "armctl"
                    assert (await receive_until(socket, lambda e: True))[0]["event"] == "hello"

        asyncio.run(sockets())


def test_a_generated_token_is_kept_0600_and_printed_once(tmp_path):
    config = tmp_path / "config"
    env = {"XDG_CONFIG_HOME": str(config)}
    with served("--arm", f"a={FAST}", journal=tmp_path / "j", listen_host="0.0.0.0", env=env) as server:
        kept = config / "armctl" / "serve-token"
        token = kept.read_text().strip()
        assert stat.S_IMODE(os.stat(kept).st_mode) == 0o600
        assert token in server.banner
        assert server.request("GET", "/api/arms")[0] == 401
        assert server.request("GET", "/api/arms", headers={"Authorization": f"Bearer {token}"})[0] == 200
    with served("--arm", f"a={FAST}", journal=tmp_path / "j", listen_host="0.0.0.0", env=env) as server:
        assert token not in server.banner and str(kept) in server.banner
        assert server.request("GET", "/api/arms", headers={"Authorization": f"Bearer {token}"})[0] == 200


def test_websocket_from_another_origin_is_refused(server):
    async def main():
        async with aiohttp.ClientSession() as session:
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await session.ws_connect(ws_url(server, "a"), headers={"Origin": "http://evil.example"})
            assert refused.value.status == 403

    asyncio.run(main())


def test_viewers_of_one_arm_are_bounded_in_number(server):
    from armctl.server.arms import MAX_VIEWERS

    async def main():
        async with aiohttp.ClientSession(connector=aiohttp.TCPConnector(limit=0)) as session:  # no pool limit
            sockets = [await session.ws_connect(ws_url(server, "a")) for _ in range(MAX_VIEWERS)]
            with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                await session.ws_connect(ws_url(server, "a"))
            assert refused.value.status == 503
            await sockets.pop().close()
            await asyncio.sleep(0.2)
            sockets.append(await session.ws_connect(ws_url(server, "a")))  # room again
            for socket in sockets:
                await socket.close()

    asyncio.run(main())
