"""``POST /api/arms/NAME/jobs?resume=ID`` holds the journal's script while it waits for its
check, as an upload holds its body: its bytes count against the server's bound on script bytes
held at once (``SCRIPTS_HELD_BYTES``), so resumes asked for together cannot hold more than
uploads may (each journal script can be 128 MiB).  Beyond the bound: 503 ``too_busy`` at once,
nothing read, nothing sent.
"""
from __future__ import annotations

import asyncio

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from test_serve_review import moves, with_client  # noqa: E402

pytestmark = pytest.mark.timeout(60)

JOB_ID = "20261128T120000-abc123"


def test_a_resume_counts_its_journal_script_against_the_bytes_held(tmp_path, monkeypatch):
    from armctl.server import app, arms

    script = moves(6_000).encode()  # 130 kB: two fit under the bound set here, three do not
    monkeypatch.setattr(app, "SCRIPTS_HELD_BYTES", 2 * len(script) + 1000, raising=False)
    journal = tmp_path / "a"
    journal.mkdir()
    (journal / f"{JOB_ID}.txt").write_bytes(script)  # a job of an earlier server: its script, no log

    async def test(client, services):
        arms._SCRIPT_WORK.acquire()  # the checker busy with a neighbour's script
        try:
            held = [asyncio.ensure_future(client.post("/api/arms/a/lint", data=script)) for _ in range(2)]
            await asyncio.sleep(0.5)
            resume = asyncio.ensure_future(client.post(f"/api/arms/a/jobs?resume={JOB_ID}"))
            done, _ = await asyncio.wait([resume], timeout=5)
            assert done, "the resume waited for the checker holding its script: the held bytes' bound does not count it"
            answer = await resume.result().json()
            assert (resume.result().status, answer["code"]) == (503, "too_busy"), answer
        finally:
            arms._SCRIPT_WORK.release()
        for upload in held:
            assert (await asyncio.wait_for(upload, 30)).status == 200
        assert not services["a"].jobs, "a refused resume started a job"

    with_client(tmp_path, test)
