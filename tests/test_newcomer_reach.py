"""Issue 26 item 10: a target beyond any plausible desktop arm — more than twice the profile's
reach from the robot origin — is a lint error (L103) even while the profile's reach is only
illustrative (elsewhere such findings are warnings): ``G1 X2000`` never runs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from armctl import Arm, ScriptError
from armctl.core.checked import check
from armctl.lint.rules import IMPLAUSIBLE_REACH_FACTOR
from armctl.host.profile import default_profile
from armctl.script import ScriptSnapshot

ARMCTL = Path(sys.executable).with_name("armctl")
START = "G1 X200 Y0 Z200 A180 B0 C0 S1500 F3000\n"


def findings(text: str):
    report = check(ScriptSnapshot("job.txt", text.encode()), default_profile())
    return [(d.code, d.severity, d.span.line) for d in report.diagnostics if d.code == "L103"]


def test_twice_the_reach_is_an_error_with_the_illustrative_profile():
    assert IMPLAUSIBLE_REACH_FACTOR == 2.0 and default_profile().workspace.reach_mm == 470.0
    assert findings(START + "G1 X2000\n") == [("L103", "error", 2)]
    assert findings(START + "G1 X900\n") == [("L103", "warning", 2)]  # 900 < 940: the illustrative numbers decide
    assert findings(START + "G1 X300 Y-900 Z400\n") == [("L103", "error", 2)]  # 1028 mm away


def test_a_worktable_origin_counts():
    assert findings(START + "G54 X1500 Y0 Z0\nG1 X600 Y0 Z200 A180 B0 C0\n") == [("L103", "error", 3)]  # robot X 2100


def test_the_message_says_why_and_names_no_illustrative_numbers():
    report = check(ScriptSnapshot("job.txt", (START + "G1 X2000\n").encode()), default_profile())
    (finding,) = [d for d in report.diagnostics if d.code == "L103"]
    assert "more than 2x the profile's reach (470 mm): beyond any desktop arm" in finding.message
    assert "illustrative" not in finding.message and finding.span.snippet == "X2000"


@pytest.mark.timeout(60)
def test_the_api_sends_nothing():
    with Arm.open("sim://?clock=virtual") as arm:
        with pytest.raises(ScriptError, match="L103"):
            arm.move(x=2000)
        assert arm._link.port.model.frames_received == []


@pytest.mark.timeout(60)
def test_the_installed_command_refuses_to_run_it(tmp_path):
    job = tmp_path / "job.txt"
    job.write_text(START + "G1 X2000\n")
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([str(ARMCTL), "run", str(job), "--port", "sim://?clock=virtual", "--no-live"],
                          capture_output=True, text=True, timeout=50, env=env)
    assert done.returncode == 1
    assert "L103" in done.stderr and "nothing was sent to the arm" in done.stderr
    moved = subprocess.run([str(ARMCTL), "move", "x=2000", "--port", "sim://?clock=virtual"],
                           capture_output=True, text=True, timeout=50, env=env)
    assert moved.returncode == 1 and "beyond any desktop arm" in moved.stderr
