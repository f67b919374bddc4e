"""The arm's per-command wait (``[timing] command_overhead_s``) below one status step: 4 ms, 7 ms.

The simulator (``sim://?profile=`` with that ``[timing]``) waits exactly the configured time before
every motion command — its time is continuous, the wait is no multiple of anything — so it can stand
in for a 4 ms or a 7 ms arm.  Checked through the ``sim://`` port the host opens, in virtual time.
"""

from __future__ import annotations

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
