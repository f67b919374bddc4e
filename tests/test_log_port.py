"""A log records its port, and a resume goes to that arm (the crash review's faults, left open).

1. A ``run --log`` did not record its port: ``armctl run JOB --resume LOG`` without ``--port``
   met whatever port was configured (armctl.toml, ARMCTL_PORT) or the built-in simulator, not
   the arm the job ran on — a user killed mid-job on a real arm could resume on another arm, or
   on the simulator, whose fresh arm "proved" every line done.  The log's job record now holds
   the port (sealed like every record); without ``--port`` the resume opens it and says so; a
   ``--port`` that is another arm's is refused (exit 2, naming both, nothing opened) unless
   ``--other-port`` says it is the same arm on another port; a log from before says its port
   is unknown and resumes as before; ``armctl decode`` shows the port.
2. ``--resume`` of a log of a job on ``sim://`` in a new process met a new simulated arm (the
   simulator's state died with the old process): the "resume" ran on a fresh arm at its home
   pose, from the line after the last one the dead arm's reports proved, or said "nothing to
   resume: every line of the job is proven executed" — claims no report of this arm made.  The
   job record of a ``sim://`` port now names the process its arm lives in (``sim_process``); a
   resume in another process is refused (exit 2, nothing opened) and says why: a simulated arm
   does not outlive its process (``armctl sim --pty`` keeps one in a process of its own).

One arm across runs in-process, as tests/test_resume_exactly_once.py keeps it (``open_port``
wrapped); the installed command in fresh processes against ``armctl sim --pty`` (an arm in a
process of its own, as a real arm outlives the host).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl import Arm
from armctl.core.joblog import seal, unseal
from armctl.errors import ResumeRefused
from armctl.ui.cli import main
from test_resume_exactly_once import _job, _job_targets, _targets_done
from journal_crash import pty_arm
from test_resume_once import URL, _stopped_job as stopped_job

pytestmark = pytest.mark.timeout(60)

OTHER = "sim://?clock=virtual&fifo_frames=150"  # another arm (another FIFO: not the same arm)
MOVED = "sim://?clock=virtual&speed_factor=1.01"  # another port (in calibration.arm_identity's eyes)
ARMCTL = Path(sys.executable).with_name("armctl")  # the installed command


def _invoke(*args, port_env: str | None = None):
    return CliRunner().invoke(main, list(args), env={"ARMCTL_PORT": port_env})


def _stopped_job(tmp_path, monkeypatch) -> dict:
    """``armctl run job.txt --port URL --log j1.log`` stopped (Ctrl-C) after 14 frames; the ports
    opened (each URL one arm, kept for the runs after)."""
    return stopped_job(tmp_path, monkeypatch, 14)


def _every_line_once(arm) -> bool:
    done = _targets_done(arm)
    collapsed = [t for k, t in enumerate(done) if k == 0 or done[k - 1] != t]  # (an idempotent re-send)
    return collapsed == _job_targets() and len(done) - len(collapsed) <= 1


def _job_record(log: Path) -> dict:
    """The log's job record (after the pause toggle a resume sends an arm it finds paused)."""
    return next(record for line in log.read_text(encoding="utf-8").splitlines()
                if (record := unseal(line)) is not None and record["dir"] == "job")


def _with_port(log: Path, port: str | None, into: Path, **fields) -> Path:
    """``log`` with its job record's port (and ``fields``) changed — None: taken out, as an
    armctl before wrote it — sealed again: what that armctl, or a run on ``port``, would have written."""
    lines = log.read_text(encoding="utf-8").splitlines()
    record = unseal(lines[0])  # (the job record: the run found the arm idle)
    assert record["dir"] == "job"
    seq = record.pop("seq")
    for key, value in {"port": port, **fields}.items():
        record.pop(key, None)
        if value is not None:
            record[key] = value
    into.write_text("\n".join([seal(record, seq), *lines[1:]]) + "\n", encoding="utf-8")
    return into


# --- in-process ------------------------------------------------------------------------------


def test_the_job_record_holds_the_port_sealed(tmp_path, monkeypatch):
    _stopped_job(tmp_path, monkeypatch)
    record = _job_record(tmp_path / "j1.log")
    assert record is not None and record["dir"] == "job"  # intact: its CRC covers the port
    assert record["port"] == URL


def test_a_resume_without_port_goes_to_the_logs_port_not_the_configured_one(tmp_path, monkeypatch):
    ports = _stopped_job(tmp_path, monkeypatch)
    resumed = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log", "--log", "j2.log", port_env=OTHER)
    assert resumed.exit_code == 0, resumed.output
    assert f"on the port j1.log records, {URL}" in resumed.output
    assert "resuming job.txt at line" in resumed.output
    assert OTHER not in ports  # the configured arm was never opened
    assert _every_line_once(ports[URL].model)
    assert _job_record(tmp_path / "j2.log")["port"] == URL  # the resume's own log: the same arm


def test_a_resume_on_another_port_is_refused_naming_both(tmp_path, monkeypatch):
    ports = _stopped_job(tmp_path, monkeypatch)
    arm = ports[URL].model
    received = len(arm.frames_received)
    refused = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log", "--port", OTHER)
    assert refused.exit_code == 2, refused.output
    assert URL in refused.output and OTHER in refused.output and "--other-port" in refused.output
    assert "Traceback" not in refused.output
    assert OTHER not in ports and len(arm.frames_received) == received  # nothing opened, nothing sent
    # the same arm under the same port, spelt with a speed of its own: the same arm (calibration.arm_identity)
    same = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log", "--port", URL + "&speed=2")
    assert "--other-port" not in same.output, same.output


def test_other_port_resumes_the_same_arm_moved_to_another_port(tmp_path, monkeypatch):
    ports = _stopped_job(tmp_path, monkeypatch)
    ports[MOVED] = ports[URL]  # the arm, replugged: another port, the same arm
    refused = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log", "--port", MOVED)
    assert refused.exit_code == 2 and "--other-port" in refused.output, refused.output
    resumed = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log", "--port", MOVED, "--other-port")
    assert resumed.exit_code == 0, resumed.output
    assert "resuming job.txt at line" in resumed.output
    assert _every_line_once(ports[URL].model)
    lonely = _invoke("run", "job.txt", "--no-live", "--port", URL, "--other-port")
    assert lonely.exit_code == 2 and "--resume" in lonely.output, lonely.output


def test_a_log_from_before_the_port_resumes_as_before_and_says_the_port_is_unknown(tmp_path, monkeypatch):
    ports = _stopped_job(tmp_path, monkeypatch)
    old = _with_port(tmp_path / "j1.log", None, tmp_path / "old.log", sim_process=None, arm=None)
    resumed = _invoke("run", "job.txt", "--no-live", "--resume", "old.log", "--port", URL)
    assert resumed.exit_code == 0, resumed.output
    assert "old.log does not record the port its job ran on" in resumed.output
    assert f"resuming on {URL}" in resumed.output
    assert _every_line_once(ports[URL].model)
    decoded = _invoke("decode", str(old))
    assert decoded.exit_code == 0 and "port unknown" in decoded.output, decoded.output


def test_decode_shows_the_port(tmp_path, monkeypatch):
    _stopped_job(tmp_path, monkeypatch)
    decoded = CliRunner().invoke(main, ["decode", "j1.log"])
    assert decoded.exit_code == 0, decoded.output
    assert f"j1.log:1: job job.txt from line 1 on port {URL}" in decoded.stderr
    as_json = CliRunner().invoke(main, ["decode", "--json", "j1.log"])
    assert f"on port {URL}" in as_json.stderr
    assert all(json.loads(line) for line in as_json.stdout.splitlines())  # stdout: the frames' JSON lines only


def test_the_api_refuses_a_log_of_another_arm(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text(_job(), encoding="utf-8")
    log = tmp_path / "j1.log"
    with Arm.open(port=URL) as arm:
        def stop(progress):
            if progress.frames_sent >= 5:
                arm.stop()

        with log.open("w", encoding="utf-8") as file:
            assert arm.run(script, on_progress=stop, log=file).outcome == "interrupted"
    with Arm.open(port=OTHER) as other:
        with pytest.raises(ResumeRefused, match=re.escape(OTHER)):
            other.run(script, resume=log)
        assert len(other._link.port.model.frames_received) == 0  # nothing sent
        # the caller's word that it is the same arm (armctl run --other-port): the point re-aimed
        from armctl import ScriptSnapshot, read_resume_point

        point = replace(read_resume_point(log, ScriptSnapshot(str(script), script.read_bytes())), port=other.url,
                        arm=None)
        assert other.run(script, resume=point).frames_sent > 0  # past the port: the log and the arm's report decide


# --- the installed command, fresh processes --------------------------------------------------


def _env(**more) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env.update(more)
    return env


def test_the_installed_command_refuses_another_port_and_opens_the_logs(tmp_path, monkeypatch):
    """A log of a job on /dev/ttyACM97 (no such device here): ``--port sim://…`` is refused,
    exit 2, naming both, before any port opens; without ``--port`` the resume goes to the log's
    port — not to ARMCTL_PORT's simulator — and says so (it is not there: exit 2, nothing sent)."""
    _stopped_job(tmp_path, monkeypatch)
    device = "/dev/ttyACM97"
    log = _with_port(tmp_path / "j1.log", device, tmp_path / "device.log", sim_process=None,  # (no sim:// arm's)
                     arm=f"device {device}")  # (its identity, as a run there records it)
    refused = subprocess.run([str(ARMCTL), "run", "job.txt", "--no-live", "--resume", str(log), "--port", URL],
                             capture_output=True, text=True, timeout=60, cwd=tmp_path, env=_env())
    assert refused.returncode == 2, refused.stderr
    assert device in refused.stderr and URL in refused.stderr and "--other-port" in refused.stderr
    assert "simulator" not in refused.stderr and "Traceback" not in refused.stderr
    logs = subprocess.run([str(ARMCTL), "run", "job.txt", "--no-live", "--resume", str(log)], capture_output=True,
                          text=True, timeout=60, cwd=tmp_path, env=_env(ARMCTL_PORT=URL))
    assert logs.returncode != 0, logs.stderr
    assert f"device.log records, {device}" in logs.stderr and f"no such device: {device}" in logs.stderr
    assert "simulator" not in logs.stderr and "Traceback" not in logs.stderr
    decoded = subprocess.run([str(ARMCTL), "decode", str(log)], capture_output=True, text=True, timeout=60, env=_env())
    assert decoded.returncode == 0 and f"on port {device}" in decoded.stderr, decoded.stderr


@pytest.mark.realtime
@pytest.mark.timeout(120)
@pytest.mark.skipif(sys.platform == "win32", reason="armctl sim --pty needs a POSIX terminal")
def test_the_installed_command_resumes_on_the_arm_the_log_ran_on(tmp_path):
    """``armctl sim --pty`` (an arm that outlives the host), a job on it with --log, then
    ``--resume`` without --port and ARMCTL_PORT set to the simulator: it resumed on the
    simulator's fresh arm and said every line was proven done.  Now it goes to the pty."""
    script = tmp_path / "job.txt"
    script.write_text("G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 Z280\nG1 X220 S1000\nG1 Y10\n")
    profile = tmp_path / "arm.toml"  # the FIFO size as `armctl probe --write` keeps it: `finished` is proven
    profile.write_text("[connector]\nfifo_frames = 200\n")
    log = tmp_path / "j1.log"
    with pty_arm("--url", "sim://?speed=10") as pty:
        run = [str(ARMCTL), "run", str(script), "--no-live", "--profile", str(profile)]
        first = subprocess.run([*run, "--port", pty, "--log", str(log)], capture_output=True, text=True, timeout=60,
                               cwd=tmp_path, env=_env())
        assert first.returncode == 0, first.stdout + first.stderr
        wrong = subprocess.run([*run, "--resume", str(log), "--port", URL], capture_output=True, text=True,
                               timeout=60, cwd=tmp_path, env=_env())
        assert wrong.returncode == 2 and pty in wrong.stderr and URL in wrong.stderr, wrong.stdout + wrong.stderr
        again = subprocess.run([*run, "--resume", str(log)], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                               env=_env(ARMCTL_PORT=URL))
        assert again.returncode == 0, again.stdout + again.stderr
        assert f"j1.log records, {pty}" in again.stderr, again.stderr
        assert "simulator" not in again.stderr and "nothing to resume" in again.stdout, again.stdout + again.stderr


# --- 2. a simulated arm does not outlive its process --------------------------------------------


GONE = "4242-another-process"  # the mark of a process that is no more


def test_a_log_of_a_simulated_arm_of_another_process_is_refused(tmp_path, monkeypatch):
    """In-process, the log as the armctl of another process wrote it (its job record's mark):
    refused, exit 2, nothing opened or sent; the arm of this process resumes its own log."""
    ports = _stopped_job(tmp_path, monkeypatch)
    arm = ports[URL].model
    received = len(arm.frames_received)
    assert isinstance(_job_record(tmp_path / "j1.log").get("sim_process"), str)  # this process's mark
    gone = _with_port(tmp_path / "j1.log", URL, tmp_path / "gone.log", sim_process=GONE)
    refused = _invoke("run", "job.txt", "--no-live", "--resume", "gone.log")
    assert refused.exit_code == 2, refused.output
    assert "does not outlive its process" in refused.output and "armctl sim --pty" in refused.output
    assert "Traceback" not in refused.output and "nothing to resume" not in refused.output
    assert len(arm.frames_received) == received
    with Arm.open(port=URL) as same:  # (the one arm of this test: open_port wrapped)
        with pytest.raises(ResumeRefused, match="does not outlive its process"):
            same.run(tmp_path / "job.txt", resume=tmp_path / "gone.log")
    assert len(arm.frames_received) == received
    own = _invoke("run", "job.txt", "--no-live", "--resume", "j1.log")  # the arm of this process: resumed
    assert own.exit_code == 0 and "resuming job.txt at line" in own.output, own.output
    assert _every_line_once(arm)


@pytest.mark.parametrize("frames", [14, None], ids=["stopped mid-job", "finished"])
def test_the_installed_command_refuses_a_simulated_arm_gone_with_its_process(tmp_path, monkeypatch, frames):
    """A job on ``sim://`` in this process (stopped mid-job, or finished), resumed by the
    installed command — another process, whose simulator is a new arm at its home pose.  It
    resumed there "from where it stands" and ran the rest, or said every line was proven
    executed; now it is refused, exit 2, before any port opens."""
    if frames is None:
        monkeypatch.chdir(tmp_path)
        (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
        assert _invoke("run", "job.txt", "--no-live", "--port", URL, "--log", "j1.log").exit_code == 0
    else:
        _stopped_job(tmp_path, monkeypatch)
    for port in ((), ("--port", URL)):
        done = subprocess.run([str(ARMCTL), "run", "job.txt", "--no-live", "--resume", "j1.log", *port],
                              capture_output=True, text=True, timeout=60, cwd=tmp_path, env=_env())
        assert done.returncode == 2, done.stdout + done.stderr
        assert "does not outlive its process" in done.stderr and URL in done.stderr, done.stderr
        assert "nothing to resume" not in done.stdout and "resuming" not in done.stderr
        assert "using the built-in simulator" not in done.stderr and "Traceback" not in done.stderr
