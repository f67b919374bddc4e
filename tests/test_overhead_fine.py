"""The arm's per-command wait (``[timing] command_overhead_s``) below one status step: 4 ms, 7 ms.

The simulator (``sim://?profile=`` with that ``[timing]``) waits exactly the configured time before
every motion command — its time is continuous, the wait is no multiple of anything — so it can stand
in for a 4 ms or a 7 ms arm.  Checked through the ``sim://`` port the host opens, in virtual time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
import serial

import armctl  # noqa: F401  (registers sim://)
from armctl.core.protocol import Delay, JointMove

pytestmark = pytest.mark.timeout(30)

COMMANDS = 20
DELAY_MS = 100.0  # longer than a frame's 50 ms on the line at 9600: the delays queue and run back to back


def _port(tmp_path, overhead_s: float):
    (tmp_path / f"arm{overhead_s}.toml").write_text(f"[timing]\ncommand_overhead_s = {overhead_s}\n")
    return serial.serial_for_url(f"sim://?clock=virtual&profile={tmp_path / f'arm{overhead_s}.toml'}", timeout=0)


def _arm_time_of_delays(tmp_path, overhead_s: float) -> tuple[float, list]:
    """Arm time from the first delay's start to the last's end, and each delay's duration."""
    with _port(tmp_path, overhead_s) as port:
        port.write(b"".join(Delay(delay_ms=DELAY_MS).encode() for _ in range(COMMANDS)))
        port.virtual_clock.advance_to(COMMANDS * (DELAY_MS / 1000 + 0.05) + 1.0)
        port.read(100_000)
        log = port.model.execution_log
    assert len(log) == COMMANDS and all(e.outcome == "done" for e in log), log
    return log[-1].end_s - log[0].start_s, [e.duration_s for e in log]


@pytest.mark.parametrize("overhead_s", [0.004, 0.007, 0.0023])
def test_a_wait_under_one_status_step_lengthens_the_arms_time_by_n_waits(tmp_path, overhead_s):
    """20 delays of 100 ms: 20 × the wait more arm time (80 ms for 4 ms), not 0 nor 20 × 5 ms."""
    bare_s, _ = _arm_time_of_delays(tmp_path, 0.0)
    waited_s, durations = _arm_time_of_delays(tmp_path, overhead_s)
    assert bare_s == pytest.approx(COMMANDS * DELAY_MS / 1000, abs=1e-9)
    assert waited_s - bare_s == pytest.approx(COMMANDS * overhead_s, abs=1e-9)
    assert durations == pytest.approx([DELAY_MS / 1000 + overhead_s] * COMMANDS, abs=1e-12)


def test_a_motion_starts_exactly_the_wait_after_its_frame_lands(tmp_path):
    """A joint move of a 4 ms arm: still until 4 ms after landing, moving just after."""
    with _port(tmp_path, 0.004) as port:
        model = port.model
        joints = model.pose.joints
        target = list(joints)
        target[4] += 5.0
        port.write(JointMove(*target, pwm_us=1500, speed_deg_s=2.0).encode())
        port.virtual_clock.advance_to(0.2)
        port.read(100_000)
        (entry,) = model.execution_log
        landed_s = entry.start_s
        executor = model.executor
        assert executor.pose_at(landed_s + 0.004 - 1e-6).joints == joints
        assert executor.pose_at(landed_s + 0.004 + 1e-3).joints[4] > joints[4]


# --- the probe: a wait under one status step --------------------------------------------------------
#
# The timed joint moves' fits (0.01° at 2°/s: a 5 ms step) sample joint 5 every 270 ms, 54 steps
# apart: every sample sits at the same phase of the step, so a move's start delay is only known to
# a step, and the probe stated 0 for any wait under 5 ms (a 4 ms and a 7 ms arm both read 5 ms).
# A chain of delays in front of a timed move carries 20 waits into its start: its start delay
# against a lone move's resolves the wait to a step / 20.

TOLERANCE_S = 0.0005


def _probe(tmp_path, overhead_s: float, options: str = "") -> dict:
    (tmp_path / "arm.toml").write_text(f"[timing]\ncommand_overhead_s = {overhead_s}\n")
    env = {**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")}
    env.pop("ARMCTL_PORT", None)
    done = subprocess.run([sys.executable, "-m", "armctl", "probe", "--yes", "--json", "--port",
                           f"sim://?{options}clock=virtual&profile={tmp_path / 'arm.toml'}"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=50)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.parametrize("overhead_s", [0.003, 0.004, 0.007, 0.0])
@pytest.mark.timeout(60)
def test_the_probe_finds_a_wait_under_one_status_step(tmp_path, overhead_s):
    found = _probe(tmp_path, overhead_s)
    waited = found["details"]["command_overhead_s"]
    assert found["command_overhead_s"] == pytest.approx(overhead_s, abs=TOLERANCE_S), waited
    assert waited["confidence"] == "sure", waited
    if not overhead_s:
        assert found["command_overhead_s"] == 0.0, waited


def test_without_room_for_the_chain_a_wait_under_one_step_is_not_resolved(tmp_path):
    """A connector of 4 frames holds no chain of delays: the lone moves cannot tell a wait under a
    step from the probe's lag, so the probe says so ("likely", "not resolved"), never a sure 0."""
    found = _probe(tmp_path, 0.0, "fifo=4&")
    waited = found["details"]["command_overhead_s"]
    assert found["command_overhead_s"] == 0.0 and waited["confidence"] == "likely", waited
    assert "under 5.0 ms, not resolved" in waited["evidence"], waited


def _fit(start_delay_s: float, waits: int = 1):
    from armctl.probe.motion import MoveFit

    return MoveFit([], 0.0, start_delay_s, 0.005, waits, 0.005)


def test_the_chain_against_the_lone_move_gives_the_wait_to_a_step_over_n():
    from armctl.probe.overhead import measured_wait

    lag_s = 0.0016
    wait = measured_wait([_fit(0.004 + lag_s), _fit(21 * 0.004 + lag_s + 0.002, waits=21)])
    assert wait.value_s == pytest.approx(0.0041) and wait.precision_s == pytest.approx(0.0005) and wait.sure, wait


def test_a_delay_lost_from_the_chain_is_not_taken_for_a_shorter_wait():
    """One delay of 100 ms lost (a FIFO smaller than measured) starts the move 100 ms + a wait early:
    the chain's answer (−1 ms) disagrees with the lone move, so the lone rule answers, likely."""
    from armctl.probe.overhead import measured_wait

    lag_s = 0.0016
    wait = measured_wait([_fit(0.004 + lag_s), _fit(20 * 0.004 - 0.1 + lag_s, waits=21)])
    assert wait.value_s == 0.005 and wait.precision_s is None and not wait.sure, wait
    assert "the chain disagrees with the lone moves" in wait.evidence, wait
