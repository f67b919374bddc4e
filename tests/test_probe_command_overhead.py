"""The probe measures the arm's per-command wait (the profile's ``[timing] command_overhead_s``),
keeps it with the arm, applies it to every command on that arm and writes it with ``--write``.

The fault: on an arm that waits 100 ms before every motion command (impersonated through
``sim://?profile=`` with that ``[timing]``; the host's own profile keeps the document's 0) the probe
measured start delays of ~100 ms but kept only ``[connector]`` values: speed_factor 1.068 and
speed_tolerance 4.0 "(the arm needs 6.03, beyond the setting's range)", and a job of 601 short
moves was estimated at 31.6 s against an arm time of 75.6 s (+139.4 %).  In virtual time, in fresh
processes of the installed command."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest

pytestmark = pytest.mark.timeout(60)

JOB = "G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [300]\nG1 Y-49 F3000\nG1 Y-50\nO<a> endrepeat\n"
ARM_TIME = re.compile(r"arm time: ([0-9.]+) s .*; estimated ([0-9.]+) s")


def _armctl(tmp_path, *args, timeout=50):
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")}
    env.pop("ARMCTL_PORT", None)
    return subprocess.run([sys.executable, "-m", "armctl", *args], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=timeout)


def _slow_arm(tmp_path, overhead_s=0.1) -> str:
    (tmp_path / "arm.toml").write_text(f"[timing]\ncommand_overhead_s = {overhead_s}\n")
    return f"sim://?clock=virtual&profile={tmp_path / 'arm.toml'}"


def _probe(tmp_path, url, *more) -> dict:
    done = _armctl(tmp_path, "probe", "--yes", "--json", "--port", url, *more)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _estimate_and_arm_time(tmp_path, url) -> tuple[float, float]:
    (tmp_path / "job.txt").write_text(JOB)
    done = _armctl(tmp_path, "-q", "run", "job.txt", "--no-live", "--port", url)
    assert done.returncode == 0, done.stdout + done.stderr
    arm_s, estimated_s = map(float, ARM_TIME.search(done.stdout + done.stderr).groups())
    return estimated_s, arm_s


def test_the_probe_measures_the_arms_wait_before_every_command(tmp_path):
    found = _probe(tmp_path, _slow_arm(tmp_path))
    overhead = found["details"]["command_overhead_s"]
    assert overhead["confidence"] == "sure" and found["command_overhead_s"] == pytest.approx(0.1, abs=0.002), overhead
    assert "start delay" in overhead["evidence"], overhead
    # the factor no longer folds the wait in (1.068 before), and the tolerance covers only what is left
    assert found["speed_factor"] == pytest.approx(1.0, abs=0.02), found["details"]["speed_factor"]
    tolerance = found["details"]["speed_tolerance"]
    assert found["speed_tolerance"] <= 1.2 and tolerance["confidence"] == "sure", tolerance
    assert "beyond the setting's range" not in tolerance["evidence"], tolerance


def test_a_probe_again_measures_the_arm_not_the_wait_it_kept(tmp_path):
    """The timed moves are fitted against the model's motion alone: with 0.1 s kept for the arm
    (and applied to the profile the probe runs with) a second probe still finds 0.1, not 0."""
    url = _slow_arm(tmp_path)
    first = _probe(tmp_path, url)
    again = _probe(tmp_path, url)
    for name in ("command_overhead_s", "speed_factor", "speed_tolerance"):
        assert again[name] == first[name], (name, again["details"][name])


def test_the_documents_arm_waits_nothing(tmp_path):
    found = _probe(tmp_path, "sim://?clock=virtual")
    assert found["command_overhead_s"] == 0.0, found["details"]["command_overhead_s"]
    assert found["speed_tolerance"] == 1.05, found["details"]["speed_tolerance"]


def test_kept_with_the_arm_the_estimate_meets_the_arm_time(tmp_path):
    """Before: estimated 31.6 s against 75.6 s of arm time (+139.4 %)."""
    url = _slow_arm(tmp_path)
    _probe(tmp_path, url)
    listed = _armctl(tmp_path, "probe", "--list")
    assert "command_overhead_s = 0.1" in listed.stdout, listed.stdout
    estimated_s, arm_s = _estimate_and_arm_time(tmp_path, url)
    assert abs(arm_s - estimated_s) <= 0.03 * arm_s, (estimated_s, arm_s)


def test_applied_to_the_profile_of_that_arm_only(tmp_path, monkeypatch):
    url = _slow_arm(tmp_path)
    _probe(tmp_path, url)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    from armctl.host.calibration import arm_profile

    profile = arm_profile(port=url, start=tmp_path)
    assert profile.timing.command_overhead_s == pytest.approx(0.1, abs=0.002)
    assert profile.source_of("timing.command_overhead_s").startswith("probed on ")
    assert arm_profile(port="sim://?clock=virtual", start=tmp_path).timing.command_overhead_s == 0.0


def test_written_with_the_connector_values_and_read_back(tmp_path):
    """--write puts it into the [connector] table that names the arm (armctl.toml has no [timing]);
    a machine with only that file (no kept calibration) applies it as [timing] command_overhead_s."""
    url = _slow_arm(tmp_path)
    _probe(tmp_path, url, "--write", "armctl.toml")
    text = (tmp_path / "armctl.toml").read_text()
    assert re.search(r"^command_overhead_s = 0\.1\b", text, re.M) and "measured_on" in text, text
    (tmp_path / "data").rename(tmp_path / "elsewhere")  # the store forgotten: the file alone
    estimated_s, arm_s = _estimate_and_arm_time(tmp_path, url)
    assert abs(arm_s - estimated_s) <= 0.03 * arm_s, (estimated_s, arm_s)


def test_a_bad_hand_written_overhead_is_refused_by_name(tmp_path):
    (tmp_path / "armctl.toml").write_text("[connector]\ncommand_overhead_s = -1\n")
    (tmp_path / "job.txt").write_text(JOB)
    done = _armctl(tmp_path, "estimate", "job.txt")
    assert done.returncode == 2 and "command_overhead_s" in done.stderr and "Traceback" not in done.stderr, done.stderr


@pytest.mark.parametrize("delays_s, stated_s", [
    ((0.1006, 0.1006, 0.0939, 0.095), 0.1),  # the 100 ms arm: the joint moves' (finest) delay
    ((0.0006, 0.0029, 0.005, 0.0021), 0.0),  # the document's arm through a pty: its lag, not a wait
    ((0.0, 0.0, -0.005, -0.0046), 0.0),  # ... in virtual time
])
def test_the_wait_is_the_finest_moves_start_delay_above_the_probes_lag(delays_s, stated_s):
    from armctl.probe.overhead import overhead_of

    fits = [(delay, resolution) for delay, resolution in zip(delays_s, (0.0053, 0.0053, 0.021, 0.021))]
    assert overhead_of(fits) == pytest.approx(stated_s)
