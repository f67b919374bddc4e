"""A move started over HTTP can be stopped over HTTP: ``POST /api/arms/NAME/stop`` stops whatever
the arm is doing (a job, or a move), as Ctrl-C does.  Found by the serve review: stop existed
only per job id, and a move kept running after its client disconnected; only Ctrl-C of the
server stopped it.  Wall clock (a move takes time only there), in this process, on an arm whose
control frames act as they land: there the abort's pause freezes the move at once (on the
document's arm it waits in the FIFO behind the move, which runs out: README, the bound on motion
after an abort).
"""

from __future__ import annotations

import asyncio
import time

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from aiohttp.test_utils import TestClient, TestServer  # noqa: E402

from armctl.aio import AsyncArm  # noqa: E402
from armctl.server.app import build_app  # noqa: E402
from armctl.server.arms import ArmService  # noqa: E402

pytestmark = [pytest.mark.timeout(60), pytest.mark.realtime]

ARM = "sim://?speed=1&control_frames=arrival"


def test_a_move_is_stopped_by_the_arms_stop(tmp_path):
    async def main():
        service = ArmService("a", ARM, await AsyncArm.open(ARM), tmp_path / "a")
        client = TestClient(TestServer(build_app({"a": service}, token=None, host="127.0.0.1")))
        await client.start_server()
        try:
            # 100 mm at F600: 10 s of motion
            moving = asyncio.ensure_future(client.post("/api/arms/a/move", json={
                "x": 210, "y": 100, "z": 300, "a": 180, "b": 0, "c": 0, "f": 600}))
            await asyncio.sleep(1.5)
            start = time.monotonic()
            stopped = await client.post("/api/arms/a/stop")
            body = await stopped.json()
            assert stopped.status == 200 and body == {"arm": "a", "stopping": True}, body
            result = await (await moving).json()
            assert result["outcome"] == "interrupted", result
            assert time.monotonic() - start < 5.0  # the move's 8 s left were not waited out
            idle = await (await client.post("/api/arms/a/stop")).json()
            assert idle == {"arm": "a", "stopping": False}  # nothing running: nothing to stop
        finally:
            await client.close()
            await service.close()

    asyncio.run(main())
