"""Review 8 of ``armctl serve``: a resume the journal's reader refuses (armctl/core/joblog.py — a
log with no job record, a log resumed already, the arm not where the log leaves it) is told in
the server's words (``?resume=ID``, a line of your own), never ``armctl run``'s ``--from-line``
and ``--resume``.  The installed command on a free loopback port (tests/serve_process.py), its
arm a simulator in virtual time; the journal's files are written as a crash or another program
leaves them."""
from __future__ import annotations

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import served  # noqa: E402

pytestmark = pytest.mark.timeout(60)

VIRTUAL = "sim://?clock=virtual"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z120\nG1 Z100\n"
CLI_WORDS = ("--resume", "--from-line", "--log", "--port")


def _finished(server) -> str:
    status, created = server.request("POST", "/api/arms/a/jobs?name=job.txt", JOB)
    assert status == 201, created
    assert server.wait_job("a", created["id"])["outcome"] == "finished"
    return created["id"]


def _refusals(tmp_path) -> dict:
    """Each refusal as a client of the server meets it: the 422's message before the job starts,
    or the job's error after its 201 (the arm's report decides, read once the job runs)."""
    from armctl.host.jobflow import mark_resumed

    journal = tmp_path / "a"
    answers = {}
    with served("--arm", f"a={VIRTUAL}", journal=tmp_path) as server:
        once, unproven = _finished(server), _finished(server)
        mark_resumed(str(journal / f"{once}.log"), 1, None)  # resumed once, by a run that kept no journal
        (journal / "nojob.txt").write_text(JOB)
        (journal / "nojob.log").write_text("")  # a run killed before its job record was durable
        # the journal up to the second frame's progress record: nothing proven done, and the arm at the
        # job's end is neither where it started nor where line 1 or 2 leaves it
        kept = (journal / f"{unproven}.log").read_text().splitlines(keepends=True)
        last = min(i for i, line in enumerate(kept) if '"dir": "progress"' in line and '"frames_sent": 2' in line)
        (journal / f"{unproven}.log").write_text("".join(kept[:last + 1]))
        for name, job_id in (("resumed already", once), ("no job record", "nojob")):
            status, refused = server.request("POST", f"/api/arms/a/jobs?resume={job_id}")
            assert status == 422, refused
            answers[name] = refused["error"]
        status, created = server.request("POST", f"/api/arms/a/jobs?resume={unproven}")
        assert status == 201, created
        ended = server.wait_job("a", created["id"])
        assert ended["outcome"] == "failed" and ended["frames_sent"] == 0, ended
        answers["not proven"] = ended["error"]
    return answers


def test_the_journal_s_refusals_speak_the_server_words(tmp_path):
    answers = _refusals(tmp_path)
    assert "resumed already" in answers["resumed already"] and "no job record" in answers["no job record"], answers
    assert "cannot prove" in answers["not proven"], answers
    for name, message in answers.items():
        assert not any(word in message for word in CLI_WORDS), (name, message)
        assert "a line of your own" in message, (name, message)
    assert "?resume=" in answers["no job record"], answers
