"""A log records the arm's identity, and a resume refuses a port whose arm is another one.

The log's job record held the port's NAME only: after a replug (USB renumbering, two arms on one
host) /dev/ttyUSB0 may be another arm, and ``armctl run JOB --resume LOG`` without ``--port``
went to it — continuing, on an arm that never ran them, the lines the first arm had not run.
Now the job record keeps ``calibration.arm_identity`` of the port as the job starts (``arm``:
a USB adapter's VID:PID and serial number); a resume whose port — the log's, or ``--port`` —
has another identity now is refused (exit 2, nothing sent) naming both, and the port where the
log's arm is now found is the ``--port`` the message gives (that port resumes, no
``--other-port``: it is the same arm); ``--other-port`` still says "it is that arm".  A log
without the identity (an older one) resumes as before and says the identity is unknown.

The USB adapters are faked at the seam ``arm_identity`` reads (``calibration.port_infos``,
pyserial's list), each device name opening the simulated arm of its serial number; the real
ports are two ``armctl sim --pty`` behind one symlink (as /dev/serial/by-id links lead to a
device): their identities are the paths the link leads to, so the link re-pointed is another arm.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from click.testing import CliRunner

import armctl.host.calibration
import armctl.host.link
from armctl import Arm
from armctl.core.joblog import seal, unseal
from armctl.errors import ResumeRefused
from armctl.ui.cli import main
from journal_crash import pty_arm
from test_resume_exactly_once import _job, _job_targets, _stop_after, _targets_done

pytestmark = pytest.mark.timeout(60)

ARMCTL = Path(sys.executable).with_name("armctl")  # the installed command
SIM = "sim://?clock=virtual"
A, B = "usb 0403:6001 serial ARM-A", "usb 0403:6001 serial ARM-B"  # arm_identity of the two adapters


class _Host:
    """Two USB arms: ``plug(serial, device)`` says which device name each adapter has now (as
    pyserial lists it); opening a device opens the simulated arm of the adapter there."""

    def __init__(self, monkeypatch):
        self.devices: dict[str, str] = {}  # device -> serial number
        self.arms: dict[str, object] = {}  # serial number -> the simulated port (its arm kept across runs)
        real_open = armctl.host.link.open_port

        def open_port(url, *args, **kwargs):
            serial = self.devices.get(url)
            if serial is None:
                return real_open(url, *args, **kwargs)
            port = self.arms.get(serial)
            if port is None:
                port = self.arms[serial] = real_open(SIM, *args, **kwargs)
            port.is_open = True  # the same arm, still where the last run left it
            return port

        monkeypatch.setattr(armctl.host.link, "open_port", open_port)
        monkeypatch.setattr(armctl.host.calibration, "port_infos", self.port_infos)

    def plug(self, **devices: str) -> None:
        self.devices = {f"/dev/{device}": serial for device, serial in devices.items()}

    def port_infos(self):
        return [SimpleNamespace(device=device, vid=0x0403, pid=0x6001, serial_number=serial, location="1-1.2")
                for device, serial in self.devices.items()]

    def sent(self, serial: str) -> int:
        port = self.arms.get(serial)
        return 0 if port is None else len(port.model.frames_received)


RUN = ("run", "job.txt", "--no-live", "--profile", "arm.toml")  # (the FIFO size as `armctl probe --write` keeps it)


def _invoke(*args):
    return CliRunner().invoke(main, list(args), env={"ARMCTL_PORT": None})


def _stopped_on_usb0(tmp_path, monkeypatch) -> _Host:
    """``armctl run job.txt --port /dev/ttyUSB0 --log j1.log`` on arm A, stopped after 14 frames."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
    (tmp_path / "arm.toml").write_text("[connector]\nfifo_frames = 200\n", encoding="utf-8")
    host = _Host(monkeypatch)
    host.plug(ttyUSB0="ARM-A", ttyUSB1="ARM-B")
    _stop_after(monkeypatch, 14)
    first = _invoke(*RUN, "--port", "/dev/ttyUSB0", "--log", "j1.log")
    assert first.exit_code == 130, first.output
    return host


def _job_record(log: Path) -> dict:
    return next(record for line in log.read_text(encoding="utf-8").splitlines()
                if (record := unseal(line)) is not None and record["dir"] == "job")


def _every_line_once(port) -> bool:
    done = _targets_done(port.model)
    collapsed = [t for k, t in enumerate(done) if k == 0 or done[k - 1] != t]  # (an idempotent re-send)
    return collapsed == _job_targets() and len(done) - len(collapsed) <= 1


# --- in-process, two USB arms ----------------------------------------------------------------------


def test_the_job_record_holds_the_identity_of_the_arm(tmp_path, monkeypatch):
    _stopped_on_usb0(tmp_path, monkeypatch)
    record = _job_record(tmp_path / "j1.log")  # intact: its CRC covers the identity
    assert record["port"] == "/dev/ttyUSB0" and record["arm"] == A
    decoded = _invoke("decode", "j1.log")
    assert decoded.exit_code == 0 and f"on port /dev/ttyUSB0 ({A})" in decoded.output, decoded.output


def test_a_name_that_leads_to_another_arm_now_is_refused_and_the_logs_arm_found(tmp_path, monkeypatch):
    """Replugged: /dev/ttyUSB0 is arm B, arm A is /dev/ttyUSB1.  Without --port the resume went
    to /dev/ttyUSB0 and ran the rest of the job on arm B."""
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    host.plug(ttyUSB0="ARM-B", ttyUSB1="ARM-A")
    sent_a = host.sent("ARM-A")
    refused = _invoke(*RUN, "--resume", "j1.log", "--log", "j2.log")
    assert refused.exit_code == 2, refused.output
    assert A in refused.output and B in refused.output and "/dev/ttyUSB0" in refused.output
    assert "--port /dev/ttyUSB1" in refused.output and "--other-port" in refused.output
    assert "Traceback" not in refused.output
    assert host.sent("ARM-B") == 0 and host.sent("ARM-A") == sent_a  # nothing sent to either arm
    # the port the message gives: the log's arm, by its identity — no --other-port needed
    resumed = _invoke(*RUN, "--resume", "j1.log", "--port", "/dev/ttyUSB1", "--log", "j2.log")
    assert resumed.exit_code == 0 and "resuming job.txt at line" in resumed.output, resumed.output
    assert _every_line_once(host.arms["ARM-A"]) and host.sent("ARM-B") == 0
    assert _job_record(tmp_path / "j2.log")["arm"] == A


def test_a_port_given_that_is_another_arm_now_is_refused_unless_other_port(tmp_path, monkeypatch):
    """--port /dev/ttyUSB0, the log's very port name, is arm B after the replug: refused (by
    name it was "the same arm"); ``--other-port`` is the user's word that it is that arm."""
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    host.plug(ttyUSB0="ARM-B", ttyUSB1="ARM-A")
    refused = _invoke(*RUN, "--resume", "j1.log", "--port", "/dev/ttyUSB0")
    assert refused.exit_code == 2, refused.output
    assert A in refused.output and B in refused.output and "--port /dev/ttyUSB1" in refused.output
    assert host.sent("ARM-B") == 0
    moved = _invoke(*RUN, "--resume", "j1.log", "--port", "/dev/ttyUSB0", "--other-port")
    assert moved.exit_code == 0 and "resuming job.txt at line" in moved.output, moved.output
    assert host.sent("ARM-B") > 0  # (the user's word: the job goes on there)


def test_the_logs_arm_not_found_is_said(tmp_path, monkeypatch):
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    host.plug(ttyUSB0="ARM-B")  # arm A unplugged, arm B renumbered to its name
    refused = _invoke(*RUN, "--resume", "j1.log")
    assert refused.exit_code == 2, refused.output
    assert "not found on this host" in refused.output and "armctl ports" in refused.output
    assert A in refused.output and B in refused.output and host.sent("ARM-B") == 0


def test_the_same_arm_on_the_same_name_resumes_as_before_and_its_log_names_it(tmp_path, monkeypatch):
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    host.plug(ttyUSB0="ARM-A")  # (arm B unplugged meanwhile: nothing to do with this job)
    resumed = _invoke(*RUN, "--resume", "j1.log", "--log", "j2.log")
    assert resumed.exit_code == 0, resumed.output
    assert "on the port j1.log records, /dev/ttyUSB0 (the arm its job ran on)" in resumed.output
    assert _every_line_once(host.arms["ARM-A"]) and host.sent("ARM-B") == 0
    assert _job_record(tmp_path / "j2.log")["arm"] == A  # the resume's own log: the same arm, by identity


def test_a_log_without_the_identity_resumes_by_name_and_says_it_cannot_check(tmp_path, monkeypatch):
    """An older log (no ``arm``): by name, as before — even on arm B after a replug, which it
    cannot know — and the note says the identity is unknown."""
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    lines = (tmp_path / "j1.log").read_text(encoding="utf-8").splitlines()
    record = unseal(lines[0])
    assert record["dir"] == "job"
    seq = record.pop("seq")
    del record["arm"]
    (tmp_path / "old.log").write_text("\n".join([seal(record, seq), *lines[1:]]) + "\n", encoding="utf-8")
    host.plug(ttyUSB0="ARM-B", ttyUSB1="ARM-A")
    resumed = _invoke(*RUN, "--resume", "old.log")
    assert resumed.exit_code == 0, resumed.output
    assert "old.log records, /dev/ttyUSB0" in resumed.output and "identity is unknown" in resumed.output
    decoded = _invoke("decode", "old.log")
    assert decoded.exit_code == 0 and "arm unknown" in decoded.output, decoded.output


def test_the_api_refuses_a_resume_on_another_arm(tmp_path, monkeypatch):
    """``Arm.run(resume=)``: the same rule (resume_port.refuse_another_arm), nothing sent."""
    host = _stopped_on_usb0(tmp_path, monkeypatch)
    host.plug(ttyUSB0="ARM-B", ttyUSB1="ARM-A")
    with Arm.open(port="/dev/ttyUSB0") as other:
        with pytest.raises(ResumeRefused, match=re.escape(B)) as refused:
            other.run(tmp_path / "job.txt", resume=tmp_path / "j1.log")
        assert "Arm.open('/dev/ttyUSB1')" in str(refused.value) and "arm=None" in str(refused.value)
    assert host.sent("ARM-B") == 0
    with Arm.open(port="/dev/ttyUSB1") as same:  # the log's arm under its new name
        assert same.run(tmp_path / "job.txt", resume=tmp_path / "j1.log").outcome.startswith("finished")
    assert _every_line_once(host.arms["ARM-A"])


# --- the installed command, fresh processes, real ports ----------------------------------------------


def _env(**more) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env.update(more)
    return env


@pytest.mark.realtime
@pytest.mark.timeout(120)
@pytest.mark.skipif(sys.platform == "win32", reason="armctl sim --pty needs a POSIX terminal")
def test_the_installed_command_refuses_a_link_that_leads_to_another_arm_now(tmp_path):
    """Two ``armctl sim --pty`` arms and one name for the arm, a symlink (as a /dev/serial/by-id
    link): a job on it, stopped; the link re-pointed at the other arm; ``--resume`` without
    --port is refused, exit 2, naming both and the first arm's pty, which resumes the job."""
    script = tmp_path / "job.txt"
    script.write_text("G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 Z280\nG1 X220 S1000\nG1 Y10\n")
    profile = tmp_path / "arm.toml"
    profile.write_text("[connector]\nfifo_frames = 200\n")
    log, link = tmp_path / "j1.log", tmp_path / "arm"
    run = [str(ARMCTL), "run", str(script), "--no-live", "--profile", str(profile)]
    with pty_arm("--url", "sim://?speed=10") as first, pty_arm("--url", "sim://?speed=10") as second:
        link.symlink_to(first)
        ran = subprocess.run([*run, "--port", str(link), "--log", str(log)], capture_output=True, text=True,
                             timeout=60, cwd=tmp_path, env=_env())
        assert ran.returncode == 0, ran.stdout + ran.stderr
        copy = tmp_path / "copy.log"  # (a log is resumed once)
        copy.write_bytes(log.read_bytes())
        same = subprocess.run([*run, "--resume", str(copy)], capture_output=True, text=True, timeout=60,
                              cwd=tmp_path, env=_env())
        assert same.returncode == 0 and "nothing to resume" in same.stdout, same.stdout + same.stderr
        link.unlink()
        link.symlink_to(second)  # the name leads to another arm now
        refused = subprocess.run([*run, "--resume", str(log)], capture_output=True, text=True, timeout=60,
                                 cwd=tmp_path, env=_env())
        assert refused.returncode == 2, refused.stdout + refused.stderr
        assert f"device {first}" in refused.stderr and f"device {second}" in refused.stderr, refused.stderr
        assert f"--port {first}" in refused.stderr and "Traceback" not in refused.stderr
        assert "resuming" not in refused.stderr and "nothing to resume" not in refused.stdout
        again = subprocess.run([*run, "--resume", str(log), "--port", first], capture_output=True, text=True,
                               timeout=60, cwd=tmp_path, env=_env())
        assert again.returncode == 0 and "nothing to resume" in again.stdout, again.stdout + again.stderr
    # before the re-pointing: the log's name and its arm agree; a pty is known by when it was made,
    # not by its path only (tests/test_review6_realtime.py), so no note says it cannot be checked
    assert f"copy.log records, {link}" in same.stderr and "only, as any arm there" not in same.stderr, same.stderr
