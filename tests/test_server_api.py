"""``armctl serve``'s HTTP API as users reach it: the installed command in a subprocess on a free
loopback port, real HTTP requests (urllib).  Skipped where the ``serve`` extra is not installed
(.ci/run installs it and runs these)."""
from __future__ import annotations

import json
import subprocess
import sys
import threading
from pathlib import Path

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import ARMCTL, served  # noqa: E402

pytestmark = [pytest.mark.realtime, pytest.mark.timeout(90)]

DATA = Path(__file__).parent / "data" / "scripts_cli"
SHORT = (DATA / "short_job.txt").read_text()
FAST = "sim://?speed=20"


def long_job(moves: int = 40) -> str:
    """A job of ``moves`` slow moves (about 1 s each of arm time), to pause and stop mid-way."""
    lines = ["G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000"]
    lines += [f"G1 X{250 + (i % 2) * 40} Y{(i % 3) * 20} F2400" for i in range(moves)]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with served("--arm", f"a={FAST}", "--arm", f"b={FAST}", journal=tmp_path_factory.mktemp("journal")) as running:
        yield running


def test_two_arms_each_run_a_job_at_once_to_finished_with_every_frame_sent(server):
    status, arms = server.request("GET", "/api/arms")
    assert status == 200 and [arm["name"] for arm in arms] == ["a", "b"]
    assert all(arm["port"] == FAST for arm in arms)
    ids = {}
    for name in ("a", "b"):
        status, created = server.request("POST", f"/api/arms/{name}/jobs?name=short_job.txt", SHORT)
        assert status == 201, created
        ids[name] = created["id"]
    for name, job_id in ids.items():
        job = server.wait_job(name, job_id)
        assert job["outcome"] == "finished", job
        assert job["frames_sent"] == job["total_frames"] == 5
        assert job["last_line_executed"] == job["last_line_sent"] == 6
        journal = Path(created["journal"]).parent.parent / name / f"{job_id}.log"
        records = [json.loads(line) for line in journal.read_text().splitlines()]
        assert records[0]["dir"] == "job" and records[0]["script"] == "short_job.txt"
        assert sum(1 for r in records if r["dir"] == "tx") == 5  # every frame written, journalled
        assert (journal.with_suffix(".txt")).read_text() == SHORT


def test_status_has_the_keys_of_status_once_json(server):
    status, report = server.request("GET", "/api/arms/a/status")
    assert status == 200
    once = subprocess.run([str(ARMCTL), "status", "--once", "--json", "--port", "sim://?clock=virtual"],
                          capture_output=True, text=True, timeout=30)
    assert set(report) == set(json.loads(once.stdout))


def test_a_bad_script_gets_line_and_column_and_is_not_run(server):
    script = (DATA / "compile_error_job.txt").read_text()
    status, lint = server.request("POST", "/api/arms/a/lint", script)
    assert status == 200 and lint["errors"] >= 1
    status, refused = server.request("POST", "/api/arms/a/jobs", script)
    assert status == 422
    first = refused["diagnostics"][0]
    assert (first["line"], first["severity"]) == (3, "error")
    assert {"line", "column", "code", "severity", "message"} <= set(first)
    assert first == lint["diagnostics"][0]
    status, jobs = server.request("GET", "/api/arms/a/jobs")
    assert all(job["name"] != "script" or job["outcome"] == "finished" for job in jobs)  # nothing new was started
    assert len(jobs) == len([j for j in jobs if j["outcome"] is not None])


def test_second_job_while_one_runs_is_409_and_pause_resume_feed_stop_work(server):
    status, created = server.request("POST", "/api/arms/b/jobs", long_job())
    assert status == 201, created
    job_id = created["id"]
    status, again = server.request("POST", "/api/arms/b/jobs", SHORT)
    assert status == 409 and again["code"] == "busy"
    status, moved = server.request("POST", "/api/arms/b/move", {"z": 200, "f": 3000})
    assert status == 409
    status, feed = server.request("POST", f"/api/arms/b/jobs/{job_id}/feed", {"percent": 150})
    assert status == 200 and feed["feed_percent"] == 150, feed
    status, paused = server.request("POST", f"/api/arms/b/jobs/{job_id}/pause")
    assert status == 200 and paused["toggle_sent"] is True
    status, resumed = server.request("POST", f"/api/arms/b/jobs/{job_id}/resume")
    assert status == 200 and resumed["toggle_sent"] is True
    status, stopped = server.request("POST", f"/api/arms/b/jobs/{job_id}/stop")
    assert status == 200
    job = server.wait_job("b", job_id)
    assert job["outcome"] == "interrupted" and job["frames_sent"] < job["total_frames"]
    assert job["resume_line"] is not None


def test_move_runs_one_line_and_refuses_bad_words(server):
    status, done = server.request("POST", "/api/arms/a/move", {"x": 230, "y": 0, "z": 200, "a": 180, "b": 0, "c": 0, "f": 3000})
    assert status == 200 and done["outcome"] == "finished" and done["last_line_executed"] == 1
    status, refused = server.request("POST", "/api/arms/a/move", {"q": 1})
    assert status == 422 and "q" in refused["error"]
    status, refused = server.request("POST", "/api/arms/a/move", {"x": "far"})
    assert status == 422


@pytest.mark.parametrize("method, path, body, code", [
    ("POST", "/api/arms/a/move", "{not json", 400),
    ("POST", "/api/arms/a/move", "[1, 2]", 400),
    ("GET", "/api/arms/nope/status", None, 404),
    ("POST", "/api/arms/nope/jobs", SHORT, 404),
    ("GET", "/api/arms/a/jobs/nope", None, 404),
    ("POST", "/api/arms/a/jobs/nope/pause", None, 404),
    ("POST", "/api/arms/a/jobs/nope/feed", None, 404),
    ("GET", "/api/nothing", None, 404),
    ("DELETE", "/api/arms", None, 405),
    ("POST", "/api/arms/a/jobs", b"G1 X1\x00\xff\n", 422),
])
def test_bad_requests_are_4xx_json_never_a_traceback(server, method, path, body, code):
    status, answer = server.request(method, path, body)
    assert status == code, answer
    assert isinstance(answer, dict) and answer["error"] and "Traceback" not in json.dumps(answer)


def test_origin_of_another_site_is_refused_on_state_changing_requests(server):
    status, answer = server.request("POST", "/api/arms/a/lint", SHORT, headers={"Origin": "http://evil.example"})
    assert status == 403 and answer["code"] == "bad_origin"
    status, _ = server.request("POST", "/api/arms/a/lint", SHORT, headers={"Origin": server.base})
    assert status == 200


def test_a_host_that_is_not_loopback_is_refused_without_a_token(server):
    """DNS rebinding: a page on another name that resolves to 127.0.0.1."""
    status, answer = server.request("GET", "/api/arms", headers={"Host": "evil.example:80"})
    assert status == 403 and answer["code"] == "bad_host"


def test_a_job_survives_a_crashed_server_and_the_next_one_resumes_it_from_its_journal(tmp_path):
    """The arm outlives the server (``armctl sim --pty``, a simulated arm on a pseudo-terminal that
    serves one client after another): the first server is killed (SIGKILL) mid-job, the second
    resumes the job from the journal at the line the log and the arm's report prove."""
    import signal
    import time

    sim = subprocess.Popen([str(ARMCTL), "sim", "--pty"], stdout=subprocess.PIPE, text=True)
    try:
        pty = sim.stdout.readline().split()[3]
        assert pty.startswith("/dev/"), pty
        journal = tmp_path / "journal"
        with served("--arm", f"a={pty}", journal=journal) as first:
            status, created = first.request("POST", "/api/arms/a/jobs?name=long.txt", long_job(10))
            assert status == 201, created
            job_id = created["id"]
            deadline = time.monotonic() + 30
            while first.request("GET", f"/api/arms/a/jobs/{job_id}")[1]["frames_sent"] < 4:
                assert time.monotonic() < deadline
                time.sleep(0.05)
            first.process.send_signal(signal.SIGKILL)  # a crash: no abort, no summary
            first.process.wait(10)
        with served("--arm", f"a={pty}", journal=journal) as second:
            status, resumed = second.request("POST", f"/api/arms/a/jobs?resume={job_id}")
            assert status == 201, resumed
            job = second.wait_job("a", resumed["id"])
            # a /dev/pts port is no sim:// to the host: its FIFO size is unprobed, so a frame
            # confirmed by time alone leaves it "finished, unproven" (armctl run says the same)
            assert job["outcome"] in ("finished", "finished, unproven"), json.dumps(job)
            assert job["frames_sent"] == job["total_frames"] and job["last_line_executed"] == 11
            assert job["name"] == "long.txt"
            assert job["total_frames"] < 11  # it went on from the journal, not from line 1
            status, answer = second.request("POST", "/api/arms/a/jobs?resume=..%2F..%2Fetc")
            assert status == 404, answer
    finally:
        sim.send_signal(signal.SIGINT)
        sim.wait(10)


def test_serve_without_the_extra_names_the_pip_command_and_exits_2():
    code = "import sys; sys.modules['aiohttp'] = None; from armctl.ui.cli import main; main(['serve'])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30)
    assert done.returncode == 2
    assert "pip install -e '.[serve]'" in done.stderr


@pytest.mark.parametrize("arguments, message", [
    (["--arm", "nope"], "NAME=PORT"),
    (["--arm", "a=sim://", "--arm", "a=sim://"], "twice"),
    (["--listen", "localhost"], "HOST:PORT"),
    (["--arm", "a=sim://?speed=nan"], "speed"),
])
def test_bad_options_exit_2_with_a_message(arguments, message, tmp_path):
    done = subprocess.run([str(ARMCTL), "serve", *arguments, "--journal-dir", str(tmp_path)],
                          capture_output=True, text=True, timeout=30)
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr


def test_serve_stops_on_sigint_with_130(tmp_path):
    with served("--arm", "a=sim://?speed=20", journal=tmp_path) as running:
        process = running.process
    assert process.returncode == 130


def test_requests_from_many_threads_at_once_all_answered(server):
    answers = []

    def ask():
        answers.append(server.request("GET", "/api/arms/a/status")[0])

    threads = [threading.Thread(target=ask) for _ in range(20)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    assert answers == [200] * 20


def test_a_body_over_the_script_size_limit_is_413(server):
    from armctl.host.inputs import MAX_INPUT_BYTES

    status, answer = server.request("POST", "/api/arms/a/lint", b"; " + bytes(MAX_INPUT_BYTES), timeout=60)
    assert status == 413 and answer["code"] == "too_large"
    status, _ = server.request("GET", "/api/arms")  # and the server goes on
    assert status == 200


def test_resuming_from_a_journal_whose_script_was_edited_is_refused_before_anything(server):
    status, created = server.request("POST", "/api/arms/a/jobs?name=short_job.txt", SHORT)
    assert status == 201
    assert server.wait_job("a", created["id"])["outcome"] == "finished"
    script = Path(created["journal"]).with_suffix(".txt")
    script.write_text(SHORT.replace("Y10", "Y20"))  # not the script the log records
    status, refused = server.request("POST", f"/api/arms/a/jobs?resume={created['id']}")
    assert status == 422 and refused["code"] == "refused", refused
    assert server.request("GET", "/api/arms")[1][0]["busy"] is False  # nothing started


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM"])
def test_a_signal_mid_job_stops_the_job_like_ctrl_c_and_exits_130(tmp_path, signal_name):
    """The job stops as armctl run's Ctrl-C stops it: no more frames, the abort sequence, the
    arm waited for — the motion queued (the 2 s lead), not the rest of the job's ~40 s."""
    import signal
    import time

    with served("--arm", "a=sim://?speed=4", journal=tmp_path) as server:
        status, created = server.request("POST", "/api/arms/a/jobs?name=long.txt", long_job(40))
        assert status == 201
        deadline = time.monotonic() + 20
        while server.request("GET", f"/api/arms/a/jobs/{created['id']}")[1]["frames_sent"] < 3:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        started = time.monotonic()
        server.process.send_signal(getattr(signal, signal_name))
        assert server.process.wait(20) == 130
        assert time.monotonic() - started < 6  # the rest of the job would take 10 s of wall time
    records = [json.loads(line) for line in Path(created["journal"]).read_text().splitlines()]
    sent = [r for r in records if r["dir"] == "tx"]
    assert 3 <= len(sent) < 41  # it stopped feeding; the journal has what went
    assert "Traceback" not in "".join(server.stderr_lines)
