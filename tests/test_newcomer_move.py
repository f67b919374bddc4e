"""Issue 26 item 1: ``armctl move z=200 [f=…]`` and ``armctl home`` through the installed
command in a fresh process, and ``Arm.home`` in-process: one line run as a job from the arm's
reported pose, ending only when the arm's reports prove it at rest."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from armctl import Arm
from armctl.host.profile import default_profile

ARMCTL = Path(sys.executable).with_name("armctl")
VIRTUAL = "sim://?clock=virtual"


def armctl(*args: str, tmp_path: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([str(ARMCTL), *args], capture_output=True, text=True, timeout=50, cwd=tmp_path, env=env)


@pytest.mark.timeout(60)
def test_move_z_from_the_shell(tmp_path):
    done = armctl("move", "z=200", "--port", VIRTUAL, tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("finished: the arm is at rest at X210.0 Y0.0 Z200.0"), done.stdout


@pytest.mark.timeout(60)
def test_move_json_and_f(tmp_path):
    done = armctl("move", "x=250", "z=150", "f=6000", "--json", "--port", VIRTUAL, tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["outcome"] == "finished" and result["frames_sent"] == 1 and result["arm_time_s"] > 0


@pytest.mark.timeout(60)
@pytest.mark.parametrize("words, code, text", [
    (["s=3000"], 1, "E005 S = 3000 is outside 500…2500"),
    (["zz=3"], 2, "did you mean 'z'?"),
    (["x"], 2, "WORD=VALUE"),
    (["x=nan"], 2, "not a finite number"),
    (["z=1", "z=2"], 2, "given twice"),
    ([], 2, "at least one word"),
])
def test_move_refuses_bad_words(tmp_path, words, code, text):
    done = armctl("move", *words, "--port", VIRTUAL, tmp_path=tmp_path)
    assert done.returncode == code, (done.stdout, done.stderr)
    assert text in done.stderr and "Traceback" not in done.stderr


@pytest.mark.timeout(60)
def test_home_from_the_shell(tmp_path):
    done = armctl("home", "--port", VIRTUAL, tmp_path=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("finished: the arm is at rest at"), done.stdout


@pytest.mark.timeout(60)
def test_api_home_after_a_move_comes_back_to_pose_0():
    pose_0 = default_profile().poses[0]
    with Arm.open(VIRTUAL) as arm:
        away = arm.move(j1=40, j2=10)
        assert away.finished
        home = arm.home()
        assert home.finished and home.frames_sent == 1
        joints = arm.status().joints_deg
    assert joints == pytest.approx(pose_0, abs=0.05)
