"""A command that opens no port (lint, estimate, plot, a dry run) is not stopped by a configured
port it would not open — one rule, ``calibration.quiet_port``: the port and its arm named, or
None.  Found by the review of "one fact in one place": ``run_job.configured_baud`` wrote the
rule again beside ``calibration._configured_arm`` and let the arm's identity fail through, so
with ``ARMCTL_PORT=socket://host`` (no port number) ``lint`` passed and ``estimate`` and
``run --dry-run`` exited 2 on a port neither opens.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main

pytestmark = pytest.mark.timeout(60)

ARMCTL = Path(sys.executable).with_name("armctl")
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260\n"
NO_ARM = "socket://host"  # resolves as a port, names no arm (no port number)


@pytest.mark.parametrize("command", [["lint"], ["estimate"], ["run", "--dry-run"]], ids=" ".join)
def test_a_configured_port_without_an_arm_stops_no_command_that_opens_none(tmp_path, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(JOB)
    result = CliRunner().invoke(main, [*command, "job.txt"], env={"ARMCTL_PORT": NO_ARM})
    assert result.exit_code == 0, result.output


def test_quiet_port_names_the_port_and_its_arm_or_none(tmp_path, monkeypatch):
    from armctl.host.calibration import quiet_port

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ARMCTL_PORT", NO_ARM)
    assert quiet_port(None) is None
    assert quiet_port("sim://?fifo=50").arm.identity == "sim://?fifo_frames=50"
    monkeypatch.setenv("ARMCTL_PORT", "")
    assert quiet_port(None) is None


def test_the_installed_command(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    env = {**os.environ, "ARMCTL_PORT": NO_ARM}
    done = subprocess.run([str(ARMCTL), "estimate", "job.txt"], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=50)
    assert done.returncode == 0 and "job time" in done.stdout, done.stderr
