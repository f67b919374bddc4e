"""``armctl serve``'s app in this process (aiohttp's test client) over virtual-clock arms: the
API's answers without a subprocess or the wall clock — jobs on two arms at once to finished,
lint, refusals, the events of a job."""
from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from aiohttp.test_utils import TestClient, TestServer  # noqa: E402

from armctl.aio import AsyncArm  # noqa: E402
from armctl.server.app import build_app  # noqa: E402
from armctl.server.arms import ArmService  # noqa: E402

pytestmark = pytest.mark.timeout(60)

SHORT = (Path(__file__).parent / "data" / "scripts_cli" / "short_job.txt").read_text()
VIRTUAL = "sim://?clock=virtual"


def with_client(tmp_path, test):
    async def main():
        services = {}
        for name in ("a", "b"):
            services[name] = ArmService(name, VIRTUAL, await AsyncArm.open(VIRTUAL), tmp_path / name)
        client = TestClient(TestServer(build_app(services, token=None, host="127.0.0.1")))
        await client.start_server()
        try:
            await test(client, services)
        finally:
            await client.close()
            for service in services.values():
                await service.close()

    asyncio.run(main())


async def finished(client, arm: str, job_id: str) -> dict:
    for _ in range(2000):
        job = await (await client.get(f"/api/arms/{arm}/jobs/{job_id}")).json()
        if job["outcome"] is not None:
            return job
        await asyncio.sleep(0.005)
    raise AssertionError(f"job {job_id} did not end")


def test_jobs_on_two_virtual_arms_at_once_finish_with_every_frame_sent(tmp_path):
    async def test(client, services):
        ids = {}
        for arm in ("a", "b"):
            response = await client.post(f"/api/arms/{arm}/jobs?name=short_job.txt", data=SHORT)
            assert response.status == 201
            ids[arm] = (await response.json())["id"]
        for arm, job_id in ids.items():
            job = await finished(client, arm, job_id)
            assert (job["outcome"], job["frames_sent"], job["total_frames"]) == ("finished", 5, 5)
            assert (tmp_path / arm / f"{job_id}.log").read_text().count('"dir": "tx"') == 5

    with_client(tmp_path, test)


def test_refusals_in_process(tmp_path):
    async def test(client, services):
        response = await client.post("/api/arms/a/jobs", data="G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 Z\n")
        assert response.status == 422
        diagnostic = (await response.json())["diagnostics"][0]
        assert (diagnostic["line"], diagnostic["column"], diagnostic["code"]) == (2, 5, "E001")
        assert services["a"].jobs == {}  # nothing started, nothing sent
        response = await client.post("/api/arms/a/move", data="{")
        assert response.status == 400 and (await response.json())["code"] == "bad_json"
        response = await client.get("/api/arms/zz/status")
        assert response.status == 404 and (await response.json())["code"] == "unknown_arm"
        response = await client.get("/api/arms/a/status")
        assert response.status == 200 and (await response.json())["joints"] == [0.0, 0.0, 0.0, 0.0, 90.0, 0.0]

    with_client(tmp_path, test)


def test_a_job_s_events_reach_a_websocket_viewer_in_order(tmp_path):
    async def test(client, services):
        socket = await client.ws_connect("/api/arms/b/events")
        assert (await socket.receive_json())["event"] == "hello"
        job_id = (await (await client.post("/api/arms/b/jobs", data=SHORT)).json())["id"]
        kinds = []
        while not kinds or kinds[-1] != "summary":
            event = await asyncio.wait_for(socket.receive_json(), 20)
            if event.get("job") == job_id:
                kinds.append(event["event"])
        assert kinds[0] == "job" and kinds[1] == "started" and set(kinds[2:-1]) <= {"progress", "note"}
        await socket.close()

    with_client(tmp_path, test)
