"""Review of trust at the edges (crashes, resumes, hostile inputs, arm variants): each fault found,
through the installed command in a fresh process and the API.

1. A network port URL urllib cannot read (``socket://127.0.0.1:99999``, ``socket://host:abc``,
   ``socket://[::1``) gave a ValueError traceback (exit 1) on ``status``, ``config``, ``run``,
   ``move`` and ``probe``: now one line naming the URL, exit 2, nothing opened.
2. ``run --resume LOG`` that finds nothing left to run (the arm rests where the log's last frame
   leaves it) said ``finished``, exit 0 — "every line of the job is proven executed" — on an arm
   whose FIFO size is not proven, where the job's own end says ``finished, unproven``: on
   ``sim://?fifo_frames=1`` the arm had dropped 2 of pick_and_place's 14 frames.  Now it ends
   ``finished, unproven`` (exit 1) there, as the job's end does, and ``finished`` where the FIFO
   size is proven.
3. ``run --dry-run --resume LOG`` printed the whole job from line 1, exit 0, ignoring --resume.
4. A second ``run --log LOG`` emptied the journal of the job still writing LOG.
5. A ``--resume`` while a queued long move still runs refused ("did not come to rest within
   9 s; nothing was sent") without saying how to go on.
6. A ``--resume`` of a run killed before its job began called the log an old one.
7. A ``--resume`` while an SD program held the arm still took it as at rest, and refused.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from armctl import Arm

from journal_crash import job_commands, pty_arm, ran

ROOT = Path(__file__).resolve().parent.parent
PICK = ROOT / "scripts" / "pick_and_place.txt"
SMALL_FIFO = "sim://?clock=virtual&fifo_frames=1"  # the profile says 200: the FIFO size is not proven
PROVEN_FIFO = "sim://?clock=virtual"


def _armctl(*args: str, cwd: Path, timeout: float = 30.0) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([sys.executable, "-m", "armctl", *args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd, env=env, stdin=subprocess.DEVNULL)


def _summary(done: subprocess.CompletedProcess) -> dict:
    return [json.loads(line) for line in done.stdout.splitlines() if '"summary"' in line][-1]


# --- 1. a network port URL urllib cannot read --------------------------------------------------

@pytest.mark.timeout(60)
@pytest.mark.parametrize("url, why", [
    ("socket://127.0.0.1:99999", "Port out of range"),
    ("socket://host:abc", "Port could not be cast"),
    ("rfc2217://127.0.0.1:-1", "Port could not be cast"),
    ("socket://[::1", "Invalid IPv6 URL"),
])
@pytest.mark.parametrize("command", [["status", "--once"], ["config"], ["move", "z=200"],
                                     ["run", str(PICK), "--no-live"], ["run", str(PICK), "--dry-run"]])
def test_bad_network_port_url_is_a_usage_error(tmp_path, monkeypatch, url, why, command):
    from click.testing import CliRunner

    from armctl.ui.cli import main

    monkeypatch.chdir(tmp_path)
    done = CliRunner().invoke(main, [*command, "--port", url], env={"ARMCTL_PORT": None})
    assert done.exception is None or isinstance(done.exception, SystemExit), done.exception  # no traceback
    assert done.exit_code == 2, (done.exit_code, done.output)
    assert url in done.output and why in done.output, done.output


def test_bad_network_port_url_through_the_command(tmp_path):
    # one of the cases above in a fresh process, as users meet it
    done = _armctl("status", "--once", "--port", "socket://127.0.0.1:99999", cwd=tmp_path)
    assert "Traceback" not in done.stderr, done.stderr
    assert done.returncode == 2 and "Port out of range" in done.stderr, (done.returncode, done.stderr)


# --- 2. --resume with nothing left claims only what is proven ----------------------------------

@pytest.mark.timeout(60)
def test_resume_with_nothing_left_on_an_unproven_fifo_is_not_finished(tmp_path):
    """The same arm (the API, in-process): the job's end said ``finished, unproven`` and the arm
    really dropped frames; the resume of its log must not turn that into ``finished``."""
    log = tmp_path / "job.log"
    with Arm.open(port=SMALL_FIFO) as arm:
        with log.open("w", encoding="utf-8") as file:
            first = arm.run(PICK, log=file)
        model = arm._link.port.model
        assert model.frames_dropped > 0 and ran(arm) != job_commands(PICK)  # lines the arm never ran
        assert first.outcome == "finished, unproven" and first.exit_code == 1
        again = arm.run(PICK, resume=log)
    assert again.frames_sent == 0
    assert again.outcome == "finished, unproven" and again.exit_code == 1 and not again.finished, again
    assert "probe" in " ".join(again.messages)


@pytest.mark.realtime
@pytest.mark.timeout(90)
@pytest.mark.skipif(sys.platform == "win32", reason="armctl sim --pty needs a POSIX terminal")
def test_resume_with_nothing_left_through_the_command(tmp_path):
    """Fresh processes, one arm that outlives them (``armctl sim --pty``; a ``sim://`` arm dies
    with its process, and a resume goes to the port its log records): a job journalled to its
    end, then ``--resume`` with the arm at rest at its last target.  With the FIFO size unproven
    (a pty is no ``sim://`` to the host) the summary is ``finished, unproven``, exit 1; with it
    proven (the profile's ``[connector]`` measured), ``finished``."""
    script = tmp_path / "home_end.txt"
    script.write_text("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X255\nG1 X260\nG1 X265\nG1 X270\n"
                      "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F30\n")
    measured = tmp_path / "arm.toml"  # the FIFO size as `armctl probe --write` keeps it
    measured.write_text("[connector]\nfifo_frames = 200\n")
    log = tmp_path / "job.log"
    with pty_arm("--url", "sim://?speed=10") as pty:
        _armctl("run", str(script), "--port", pty, "--no-live", "--log", str(log), cwd=tmp_path)
        assert '"job"' in log.read_text()
        unproven = _armctl("run", str(script), "--resume", str(log), "--json", cwd=tmp_path)
        assert "Traceback" not in unproven.stderr
        assert unproven.returncode == 1, (unproven.stdout, unproven.stderr)
        summary = _summary(unproven)
        assert summary["outcome"] == "finished, unproven" and summary["exit_code"] == 1 and summary["frames_sent"] == 0
        proven = _armctl("run", str(script), "--resume", str(log), "--profile", str(measured), "--json", cwd=tmp_path)
        assert proven.returncode == 0, (proven.stdout, proven.stderr)
        assert _summary(proven)["outcome"] == "finished"


# --- 3. --resume with --dry-run -------------------------------------------------------------------

@pytest.mark.timeout(60)
def test_resume_with_dry_run_is_refused_not_ignored(tmp_path):
    """A dry run printed the whole job from its first line, exit 0, as if --resume were not given:
    what the resume would send depends on the arm's report, which a dry run never reads."""
    log = tmp_path / "job.log"
    _armctl("run", str(PICK), "--port", PROVEN_FIFO, "--no-live", "--log", str(log), cwd=tmp_path)
    done = _armctl("run", str(PICK), "--dry-run", "--resume", str(log), cwd=tmp_path)
    assert "Traceback" not in done.stderr
    assert done.returncode == 2, (done.returncode, done.stdout[:500], done.stderr)
    assert "--resume" in done.stderr and "--dry-run" in done.stderr and done.stdout == ""


# --- 4. two runs given one --log ------------------------------------------------------------------

@pytest.mark.timeout(60)
def test_a_log_another_run_writes_is_not_truncated(tmp_path):
    """A second ``run --log LOG`` while a job journals to LOG emptied the file under it (the first
    job's records then went on at their old offsets: NUL bytes, and its resume refused as damaged).
    The running job holds a lock on its log; a second run is refused, exit 2, nothing sent."""
    fcntl = pytest.importorskip("fcntl")
    log = tmp_path / "job.log"
    first = _armctl("run", str(PICK), "--port", PROVEN_FIFO, "--no-live", "--log", str(log), cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    journal = log.read_bytes()
    with log.open("a") as held:  # the lock the running job holds (armctl run --log, in another process)
        fcntl.flock(held.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        second = _armctl("run", str(PICK), "--port", PROVEN_FIFO, "--no-live", "--log", str(log), cwd=tmp_path)
    assert "Traceback" not in second.stderr
    assert second.returncode == 2, (second.returncode, second.stdout, second.stderr)
    assert "another armctl" in second.stderr and "frames:" not in second.stdout
    assert log.read_bytes() == journal  # the running job's journal, untouched
    again = _armctl("run", str(PICK), "--port", PROVEN_FIFO, "--no-live", "--log", str(log), cwd=tmp_path)
    assert again.returncode == 0 and log.read_bytes().count(b'"dir": "job"') == 1  # once free, emptied and written


# --- 5. --resume while a long move still runs -----------------------------------------------------

JOB = """\
G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000
G1 X250 Y100 Z250 F600
G1 X250 Y-100 Z150 F6000
"""


def _served_arm(stats: Path) -> tuple[subprocess.Popen, str]:
    """``armctl sim --pty --stats`` in its own process: an arm that outlives the host's processes."""
    sim = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--stats", str(stats)],
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = sim.stdout.readline()  # "simulated arm on /dev/pts/N (Ctrl-C to stop)"
    return sim, line.split(" on ", 1)[1].split(" ", 1)[0]


def _killed_after(script: Path, pty: str, log: Path, frames: int, *options: str) -> None:
    """``armctl run SCRIPT --log LOG [OPTIONS]`` on the served arm, killed (SIGKILL) just after its
    ``frames``-th frame left: the host dies, the arm runs out its queue."""
    import signal

    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    host = subprocess.Popen([sys.executable, "-m", "armctl", "run", str(script), "--port", pty, "--log", str(log),
                             "--no-live", *options], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=log.parent)
    deadline = time.monotonic() + 30
    while (not log.exists() or log.read_text().count('"dir": "tx"') < frames) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)  # the last frame's bytes on the wire (50 ms at 9600 baud)
    host.send_signal(signal.SIGKILL)
    host.wait()
    assert log.read_text().count('"dir": "tx"') == frames


@pytest.mark.realtime
@pytest.mark.timeout(90)
def test_a_resume_while_the_arm_still_moves_says_how_to_go_on(tmp_path):
    """kill -9 of ``armctl run --log`` while a 14-second move runs (the arm in another process,
    ``armctl sim --pty``), then ``--resume`` at once: it waits a fixed time for the arm to come to
    rest (--timeout + 2 x lead + slack: 9 s by default), and refused with "did not come to rest within 9 s;
    nothing was sent" and nothing more.  It still refuses with nothing sent, and says how to go on."""
    signal = pytest.importorskip("signal")
    pytest.importorskip("termios")
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    log, stats = tmp_path / "job.log", tmp_path / "stats.json"
    sim, pty = _served_arm(stats)
    try:
        # a short lead and --timeout: the resume waits 1 + 2 x 0.5 + 2 s for rest while the move runs on for 12 s
        _killed_after(script, pty, log, 2, "--lead", "0.5")
        done = _armctl("run", str(script), "--port", pty, "--resume", str(log), "--timeout", "1", "--lead", "0.5",
                       cwd=tmp_path)
    finally:
        sim.send_signal(signal.SIGINT)
        sim.wait(timeout=30)
    assert "Traceback" not in done.stderr
    assert done.returncode == 1, (done.returncode, done.stdout, done.stderr)
    assert "did not come to rest" in done.stderr and "run the resume again" in done.stderr, done.stderr
    assert len(json.loads(stats.read_text())["frames"]) == 2  # nothing sent by the resume


# --- 6. --resume of a run killed before its job began ---------------------------------------------

@pytest.mark.timeout(60)
def test_a_log_of_a_run_killed_before_its_job_began_says_nothing_was_sent(tmp_path):
    """kill -9 in the first second of ``armctl run --log`` leaves the log empty (or only status
    reads): the refusal said "it has no job record (written by `armctl run --log` since --resume
    exists)", which reads as an old log; it now says no frame of the job was sent and to start over."""
    log = tmp_path / "job.log"
    log.write_text("")
    done = _armctl("run", str(PICK), "--port", PROVEN_FIFO, "--resume", str(log), cwd=tmp_path)
    assert "Traceback" not in done.stderr
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert "no frame of the job was sent" in done.stderr and "from its start" in done.stderr, done.stderr


# --- 7. --resume while an SD program runs ---------------------------------------------------------

@pytest.mark.realtime
@pytest.mark.timeout(90)
def test_a_resume_waits_for_an_sd_program_to_end(tmp_path):
    """kill -9 of ``armctl run scripts/sd_program.txt --log`` once its 5 frames are written (the
    arm in ``armctl sim --pty``: it runs out its queue, PROGRAM 1 holding it 4 s), then
    ``--resume`` at once: the resume took the arm, standing still while the program ran, as at
    rest, found it at no frame's end and refused ("not at rest where the log's last frame (15)
    leaves it … continue by hand with --from-line").  An SD program's advancing run position is
    work, as at a job's end: the resume waits it out and finds the job done, sending nothing."""
    signal = pytest.importorskip("signal")
    pytest.importorskip("termios")
    script = ROOT / "scripts" / "sd_program.txt"
    log, stats = tmp_path / "job.log", tmp_path / "stats.json"
    sim, pty = _served_arm(stats)
    try:
        _killed_after(script, pty, log, 5)
        done = _armctl("run", str(script), "--port", pty, "--resume", str(log), "--json", cwd=tmp_path)
    finally:
        sim.send_signal(signal.SIGINT)
        sim.wait(timeout=30)
    assert "Traceback" not in done.stderr
    assert "nothing to resume" in done.stderr, (done.returncode, done.stderr)
    assert _summary(done)["frames_sent"] == 0
    stats_data = json.loads(stats.read_text())
    assert len(stats_data["frames"]) == 5 and [e[3] for e in stats_data["executions"]].count("done") == 5


@pytest.mark.timeout(60)
@pytest.mark.parametrize("url", ["socket://127.0.0.1", "socket://:5555", "rfc2217://localhost"])
def test_a_network_port_url_without_host_or_port_says_so(tmp_path, monkeypatch, url):
    # socket://127.0.0.1 gave pyserial's "'<=' not supported between instances of 'int' and 'NoneType'"
    from click.testing import CliRunner

    from armctl.ui.cli import main

    monkeypatch.chdir(tmp_path)
    done = CliRunner().invoke(main, ["status", "--once", "--port", url], env={"ARMCTL_PORT": None})
    assert done.exit_code == 2 and "needs a host and a port number" in done.output, done.output
