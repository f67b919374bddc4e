"""The arm on a device port is read once a run: its identity (pyserial's port list) and what
``armctl probe`` kept for it (the store's file).  Found by the review of "one fact in one place":
``armctl run --port /dev/ttyUSB0`` listed the ports three times — for the arm's profile, for the
line rate the probe kept (``probed_baud``) and for the job record of its ``--log`` — and read the
store twice; a resume listed them four times, ``estimate`` and a dry run twice.  Now the port chosen once carries its arm
(``calibration.with_arm``: ``PortChoice.arm``), and each of them reads it there.

The USB adapter is faked at the seam the identity reads (``calibration.port_infos``); the device
opens the simulated arm on a virtual clock.
"""

from __future__ import annotations

import json
from collections import Counter
from types import SimpleNamespace

import pytest
from click.testing import CliRunner

import armctl.host.calibration
import armctl.host.link
from armctl.ui.cli import main

pytestmark = pytest.mark.timeout(60)

DEVICE, ARM = "/dev/ttyUSB7", "usb 0403:6001 serial ONCE"
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260\nG1 X250\n"


@pytest.fixture
def reads(monkeypatch, tmp_path):
    """Counts of pyserial listings and store reads while the fake adapter is plugged."""
    counted: Counter = Counter()
    real_open, real_load = armctl.host.link.open_port, armctl.host.calibration.load

    def port_infos():
        counted["listings"] += 1
        return [SimpleNamespace(device=DEVICE, vid=0x0403, pid=0x6001, serial_number="ONCE", location="1-1")]

    def load(arm, directory=None):
        counted["store reads"] += 1
        return real_load(arm, directory)

    monkeypatch.setattr(armctl.host.calibration, "port_infos", port_infos)
    monkeypatch.setattr(armctl.host.calibration, "load", load)
    monkeypatch.setattr(armctl.host.link, "open_port", lambda url, *a, **k: real_open(
        "sim://?clock=virtual" if url == DEVICE else url, *a, **k))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(JOB)
    return counted


def test_a_run_on_a_device_reads_its_arm_once(reads):
    result = CliRunner().invoke(main, ["run", "job.txt", "--port", DEVICE, "--no-live", "--log", "job.log"])
    assert result.exit_code in (0, 1), result.output  # (finished, unproven: the FIFO size is not probed)
    assert json.loads(open("job.log").readline())["arm"] == ARM
    assert reads == {"listings": 1, "store reads": 1}


@pytest.mark.parametrize("command", [["estimate"], ["run", "--dry-run"], ["lint"]], ids=" ".join)
def test_a_command_that_opens_none_reads_the_configured_arm_once(reads, monkeypatch, command):
    monkeypatch.setenv("ARMCTL_PORT", DEVICE)
    result = CliRunner().invoke(main, [*command, "job.txt"])
    assert result.exit_code == 0, result.output
    assert reads == {"listings": 1, "store reads": 1}


def test_a_resume_on_a_device_reads_its_arm_once(reads):
    CliRunner().invoke(main, ["run", "job.txt", "--port", DEVICE, "--no-live", "--log", "job.log"])
    reads.clear()
    result = CliRunner().invoke(main, ["run", "job.txt", "--resume", "job.log", "--no-live"])
    assert "nothing to resume" in result.output, result.output
    assert reads == {"listings": 1, "store reads": 1}


def test_the_summary_says_what_a_probe_would_prove_from_the_engine_not_from_its_text(reads):
    """The end of a job decides whether a probe answers why it is unproven (``RunView.probe_answers``,
    armctl/core/job_end.py); the summary reads that, where it searched the notes' text for the
    hint.  On the unprobed device the FIFO size is the document's: the hint, and the run's
    ``--json`` summary holds the same note."""
    from armctl.core.job_end import PROBE_HINT

    result = CliRunner().invoke(main, ["run", "job.txt", "--port", DEVICE, "--no-live"])
    assert result.exit_code == 1, result.output
    assert (f"finished, unproven: the arm is at rest at the last target, but what proves the job ran rests on settings "
            f"not measured on this arm (the note above); {PROBE_HINT}") in result.output


def test_the_summary_without_a_probe_to_answer(monkeypatch):
    """An unproven end a probe does not answer (an SD program never seen running) names no probe,
    whatever words its notes hold."""
    from types import SimpleNamespace

    from armctl.core.job_end import PROBE_HINT
    from armctl.ui import run_job

    lines: list = []
    monkeypatch.setattr(run_job.click, "echo", lambda text="", err=False: lines.append(text))
    result = SimpleNamespace(frames_sent=3, total_frames=3, frames_by_reports=3, frames_by_time=0, frames_unseen=0,
                             messages=(f"finished, unproven: something else ({PROBE_HINT} is no help here)",),
                             finished=False, outcome="finished, unproven", exit_code=1)
    view = SimpleNamespace(arm_time_s=None, probe_answers=False)
    assert run_job._summary(result, view, 1.0, SimpleNamespace(job_s=1.0), None) == 1
    assert lines[-1] == ("finished, unproven: the arm is at rest at the last target, but its reports do not prove "
                         "every frame ran (the note above)")
