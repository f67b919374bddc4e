"""What ``armctl probe`` keeps and writes over what an arm already has: ``--write`` into an
armctl.toml whose ``[connector]`` was measured on another arm, and a probe without motion over a
verified kinematics.

The fault: the probe of arm A (waits 100 ms before every command) wrote its seven values with
``measured_on = A``; ``armctl probe --no-motion --write`` of arm B then set ``measured_on = B`` and
the values it measured, and left A's ``speed_factor``, ``speed_tolerance`` and
``command_overhead_s = 0.1`` in the table, now naming B: ``armctl config`` on B showed
``timing.command_overhead_s 0.1 (project: armctl.toml)`` for an arm that waits nothing.  In
virtual time, through the installed command in fresh processes."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib

import pytest

pytestmark = pytest.mark.timeout(60)


def _armctl(tmp_path, *args):
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")}
    env.pop("ARMCTL_PORT", None)
    return subprocess.run([sys.executable, "-m", "armctl", *args], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=50)


def test_values_measured_on_another_arm_are_not_left_naming_this_one(tmp_path):
    (tmp_path / "a.toml").write_text("[timing]\ncommand_overhead_s = 0.1\n")
    arm_a, arm_b = "sim://?clock=virtual&profile=a.toml", "sim://?clock=virtual&fifo=50"
    assert _armctl(tmp_path, "probe", "--yes", "--json", "--port", arm_a, "--write", "armctl.toml").returncode == 0
    (tmp_path / "armctl.toml").write_text("# the project's file\n" + (tmp_path / "armctl.toml").read_text())
    done = _armctl(tmp_path, "probe", "--no-motion", "--json", "--port", arm_b, "--write", "armctl.toml")
    assert done.returncode == 0, done.stderr
    table = tomllib.loads((tmp_path / "armctl.toml").read_text())["connector"]
    assert table["measured_on"] == "sim://?fifo_frames=50" and table["fifo_frames"] == 50, table
    for name in ("speed_factor", "speed_tolerance", "command_overhead_s"):
        assert name not in table, (name, table)
    assert "speed_factor" in done.stderr and "another arm" in done.stderr, done.stderr
    assert (tmp_path / "armctl.toml").read_text().startswith("# the project's file\n")
    shown = _armctl(tmp_path, "config", "--port", arm_b).stdout
    assert "timing.command_overhead_s 0.0" in " ".join(shown.split()), shown


def test_the_same_arm_keeps_what_a_probe_without_motion_did_not_measure(tmp_path):
    (tmp_path / "a.toml").write_text("[timing]\ncommand_overhead_s = 0.1\n")
    arm_a = "sim://?clock=virtual&profile=a.toml"
    assert _armctl(tmp_path, "probe", "--yes", "--json", "--port", arm_a, "--write", "armctl.toml").returncode == 0
    assert _armctl(tmp_path, "probe", "--no-motion", "--json", "--port", arm_a, "--write", "armctl.toml").returncode == 0
    table = tomllib.loads((tmp_path / "armctl.toml").read_text())["connector"]
    assert table["command_overhead_s"] == 0.1 and table["speed_factor"] == pytest.approx(1.0, abs=0.02), table


def test_a_probe_without_motion_does_not_unverify_the_kinematics(tmp_path):
    """A probe with motion verified the kinematics at 3 poses (true, sure); ``--no-motion`` then sees
    one pose, which agrees: false, "likely" (one pose is not proof), and it replaced the true in the
    store and in the file — the streamer then trusts no sighting of a path on that arm.  One
    agreeing pose proves nothing against it: the true stays."""
    arm = "sim://?clock=virtual&fifo=50"
    assert _armctl(tmp_path, "probe", "--yes", "--json", "--port", arm, "--write", "armctl.toml").returncode == 0
    done = _armctl(tmp_path, "probe", "--no-motion", "--json", "--port", arm, "--write", "armctl.toml")
    assert done.returncode == 0, done.stderr
    assert tomllib.loads((tmp_path / "armctl.toml").read_text())["connector"]["kinematics_verified"] is True
    (tmp_path / "armctl.toml").unlink()
    listed = _armctl(tmp_path, "probe", "--list").stdout
    assert "kinematics_verified = true" in listed, listed
