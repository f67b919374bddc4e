"""Review of ``armctl serve`` as its users meet it: a refused resume in the server's words, jog
messages during the shutdown wait, a ``dropped`` event on the page.  The installed command on a
free loopback port (tests/serve_process.py)."""
from __future__ import annotations

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import served  # noqa: E402

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
