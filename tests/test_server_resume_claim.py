"""The server's resume holds the log it continues, as ``armctl run --resume`` and ``Arm.run(resume=)``
do (``log_lock.resume_claim``): another resume of the same log while this one runs — from the
command line, or a second request — is refused before anything is sent.  Found while fixing the
crash review's "a log is resumed once": the server read the log and handed the job a
``ResumePoint``, which takes no lock.
"""

from __future__ import annotations

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

import asyncio  # noqa: E402

from armctl.host.log_lock import journal_in_use, resume_claim  # noqa: E402
from test_server_inprocess import SHORT, finished, with_client  # noqa: E402

pytestmark = pytest.mark.timeout(60)


def test_a_resume_of_a_log_another_resume_holds_is_refused(tmp_path):
    async def test(client, services):
        response = await client.post("/api/arms/a/jobs?name=short_job.txt", data=SHORT)
        assert response.status == 201
        job_id = (await response.json())["id"]
        await finished(client, "a", job_id)
        log = services["a"].journal_dir / f"{job_id}.log"
        with resume_claim(str(log)):  # another armctl resuming it now
            refused = await client.post(f"/api/arms/a/jobs?resume={job_id}")
            body = await refused.json()
            assert refused.status == 422, body
            assert "another armctl is resuming it" in body["error"], body
        # let go, the resume reads it (the job finished: nothing to resume)
        again = await client.post(f"/api/arms/a/jobs?resume={job_id}")
        assert again.status == 201, await again.json()

    with_client(tmp_path, test)


LONG = "G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\n" + "".join(f"G1 X{210 + (k % 2) * 10} F600\n" for k in range(60))


def test_the_log_a_resume_continues_is_held_while_the_resumed_job_runs(tmp_path):
    async def test(client, services):
        response = await client.post("/api/arms/a/jobs?name=long.txt", data=LONG)
        job_id = (await response.json())["id"]
        for _ in range(2000):  # stopped once a few frames went
            job = await (await client.get(f"/api/arms/a/jobs/{job_id}")).json()
            if (job.get("frames_sent") or 0) >= 5:
                break
            await asyncio.sleep(0.002)
        await client.post(f"/api/arms/a/jobs/{job_id}/stop")
        await finished(client, "a", job_id)
        log = str(services["a"].journal_dir / f"{job_id}.log")
        assert not journal_in_use(log)
        resumed = await client.post(f"/api/arms/a/jobs?resume={job_id}")
        assert resumed.status == 201, await resumed.json()
        held = journal_in_use(log)  # while the resumed job runs: another resume would be refused
        await finished(client, "a", (await resumed.json())["id"])
        assert held
        assert not journal_in_use(log)  # let go when it ended

    with_client(tmp_path, test)
