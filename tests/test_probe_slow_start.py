"""The probe on an arm that takes a while before every command (the profile's
``[timing] command_overhead_s``, impersonated through ``sim://?profile=``): what it measures
there, and how sure it says it is."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from armctl.core.profile_model import SPEED_TOLERANCE_RANGE
from armctl.core.streamer import FRAME_SLACK_S, SLOWEST_ARM_FACTOR

pytestmark = pytest.mark.timeout(60)


def _probe(tmp_path, overhead_s: float, baud: int) -> dict:
    """``armctl probe --json`` in a fresh process on an arm that takes ``overhead_s`` before every command."""
    (tmp_path / "arm.toml").write_text(f"[timing]\ncommand_overhead_s = {overhead_s}\n")
    url = f"sim://?clock=virtual&profile=arm.toml&baud={baud}"
    done = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", url, "--baud", str(baud), "--yes", "--json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    return {"rc": done.returncode, "stderr": done.stderr, **json.loads(done.stdout)}


def test_a_speed_factor_whose_spread_is_larger_than_itself_is_never_sure(tmp_path):
    """At 115200 baud on an arm that takes 50 ms before every command the probe read speed_factor
    2.53 ±3 (moves 7.01, 1.03, 1.04, 1.04: the first began while the arm still ran the FIFO
    step's frames) and called it "sure", and kept it.  The confidence follows the spread."""
    found = _probe(tmp_path, 0.050, 115200)
    factor = found["details"]["speed_factor"]
    value, precision = factor["measured"], factor["data"]["precision"]
    assert factor["confidence"] != "sure" or precision <= 0.05 * value, factor
    assert found["speed_factor"] is None or precision <= value / 2, factor


@pytest.mark.parametrize("value, precision, sure", [
    (2.53, 3.0, "unsure"), (1.0, 0.5, "likely"), (1.0, 0.51, "unsure"), (1.3, 0.3, "likely"),
    (1.0, 0.05, "sure"), (1.0, 0.01, "sure"), (2.0, 0.11, "likely"),
])
def test_how_sure_a_speed_factor_is_follows_its_spread(value, precision, sure):
    from armctl.probe.motion import factor_confidence

    assert factor_confidence(value, precision) == sure


@pytest.mark.parametrize("overhead_s, baud", [(0.100, 9600), (0.100, 115200), (0.050, 115200), (0.500, 9600)])
def test_an_arm_that_takes_a_while_before_every_command_is_measured(tmp_path, overhead_s, baud):
    """An arm that takes 100 ms before every command (a PWM-only frame that changes nothing
    included): the FIFO step took the quiet of its repeated frames for the end of a round —
    fifo_frames 2 "sure" at 9600 (15 at 115200, "not consistent" at 50 ms) — and the timed move
    then began while the arm still ran them: "the arm did not finish a 2.5 s move within 4x that
    time: stopped probing", exit 1.  Now each round waits out the repeats at round 1's pace.  An arm
    that takes 0.5 s runs a round's 200 frames in over 100 s: a round was given up 60 s after its
    delay ("the PWM had not settled 60 s after the delay", exit 1, the PWM not put back); it is
    given up 60 s after the last news now."""
    found = _probe(tmp_path, overhead_s, baud)
    assert found["rc"] == 0 and found["details"]["stopped"] is None, found["stderr"]
    assert found["fifo_frames"] == 200, found["details"]["fifo_frames"]
    factor = found["details"]["speed_factor"]
    assert min(factor["data"]["start_delay_s"]) > overhead_s * 0.9, factor  # every move's start delay measured
    # the wait is stated (tests/test_probe_command_overhead.py), so the factor no longer folds it
    # in (1.07 before) and the tolerance covers only what is left of the start delays (4.0 before,
    # "beyond the setting's range", where 1 + 0.1 s × (2 − 1) / 20 ms = 6 was needed)
    assert found["command_overhead_s"] == pytest.approx(overhead_s, abs=0.002), found["details"]["command_overhead_s"]
    assert factor["confidence"] == "sure" and found["speed_factor"] == pytest.approx(1.0, abs=0.02), factor
    left_s = max(factor["data"]["start_delay_s"]) - found["command_overhead_s"]
    excess = (found["speed_tolerance"] - 1) * FRAME_SLACK_S / (SLOWEST_ARM_FACTOR - 1)
    assert excess >= left_s and found["speed_tolerance"] < SPEED_TOLERANCE_RANGE[1], found["details"]["speed_tolerance"]


@pytest.mark.parametrize("precision, sure", [(0.01, "sure"), (0.3, "likely"), (3.0, "unsure")])
def test_the_tolerance_is_no_surer_than_the_factor_it_is_relative_to(precision, sure):
    """A factor of 2.53 ±3 gave speed_tolerance 3.38, "sure" (kept), relative to a factor not stated."""
    from armctl.probe.motion import tolerance_finding

    found = tolerance_finding(2.53, precision, [0.0])
    assert found.confidence == sure, found.evidence


@pytest.mark.parametrize("seed", [2, 6])
def test_a_corrupted_status_frame_does_not_end_a_round_early(tmp_path, seed):
    """On the 100 ms arm with 15 % of the status frames corrupted (sim://?corrupt=0.15&seed=2 or 6) a
    corrupted PWM just after the delay's end passed for round 1's first step (the pace: 0.05 s where
    a frame takes 0.4 s), the quiet of the next block's repeats for the round's end: fifo_frames 2,
    "sure" (the arm holds 200), and the timed move then began while the arm still ran the fillers
    (exit 1).  A corrupted frame is a blip off the sequence sent: the round's steps count only new
    values further along it."""
    (tmp_path / "arm.toml").write_text("[timing]\ncommand_overhead_s = 0.1\n")
    url = f"sim://?clock=virtual&profile=arm.toml&corrupt=0.15&seed={seed}"
    done = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", url, "--yes", "--json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    found = json.loads(done.stdout)
    fifo = found["details"]["fifo_frames"]
    assert fifo["measured"] in (None, 200), fifo
    assert done.returncode == 0 and found["details"]["stopped"] is None, done.stderr


def test_a_corrupted_sample_does_not_tilt_a_timed_move(tmp_path):
    """On the 100 ms arm with corrupt=0.15&seed=5 one corrupted joint frame read 0.335 s into the
    second joint move 1 ms after it landed: that move's fit tilted to a start delay of -23.8 ms (the
    others 100.6, 92.0, 95.0), the least of the joint moves', so command_overhead_s was 0 and the
    factor, the wait folded in again, 1.067 "sure" for an arm at 1.0.  A sample off the fitted line
    by more than two status steps (and the clock's uncertainty) is left out, and the fit redone."""
    (tmp_path / "arm.toml").write_text("[timing]\ncommand_overhead_s = 0.1\n")
    url = "sim://?clock=virtual&profile=arm.toml&corrupt=0.15&seed=5"
    done = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", url, "--yes", "--json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    found = json.loads(done.stdout)
    assert done.returncode == 0, done.stderr
    assert found["command_overhead_s"] == pytest.approx(0.1, abs=0.002), found["details"]["command_overhead_s"]
    factor = found["details"]["speed_factor"]
    assert factor["confidence"] != "sure" or abs(factor["measured"] - 1.0) <= factor["data"]["precision"], factor


@pytest.mark.parametrize("interrupt_at_s", [40.0, 170.0])
def test_ctrl_c_in_a_fifo_round_of_a_slow_arm_puts_the_pwm_back(tmp_path, monkeypatch, interrupt_at_s):
    """Ctrl-C (the stop event) at 40 s (round 1) or 170 s (round 2's 192 leading repeats) of the
    probe of an arm that takes 0.5 s before every command: the restore step took 1.5 s of quiet
    for the end of what was queued — a block's repeats take 8 s, round 2's leading ones 100 s —
    put the PWM back behind them, waited 15 s and said "NOT as found: PWM" (1525 or 1565 for 1500).
    It waits at the round's pace now."""
    import armctl.probe.host as host

    (tmp_path / "arm.toml").write_text("[timing]\ncommand_overhead_s = 0.5\n")
    monkeypatch.chdir(tmp_path)
    drive = host.drive

    def interrupting(link, probe, inbox, progress=None, stop=None):
        def hook(probe):
            if probe.arm_time_s >= interrupt_at_s:
                stop.set()
        return drive(link, probe, inbox, hook, stop)

    monkeypatch.setattr(host, "drive", interrupting)
    from click.testing import CliRunner

    from armctl.ui.cli import main

    done = CliRunner().invoke(main, ["probe", "--yes", "--port", "sim://?clock=virtual&profile=arm.toml"])
    assert done.exit_code == 130, done.output
    assert "as found: worktable origin, PWM, running (not paused), joints" in done.output, done.output
    assert "NOT as found" not in done.output, done.output
