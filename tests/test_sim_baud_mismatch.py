"""``sim://?baud=R`` opened at another rate impersonates an arm on a line set to the wrong rate:
each end reads the other's bytes as noise.  Before, the simulated arm ran at R whatever rate the
host's port was set to, so the host timed a 115200 line as 9600 (``armctl run`` without
``--baud``): the probe stated wrong values "sure" (a speed factor of 0.964, an overhead of 45 ms
for 100 ms) and kept 9600 for that arm, and a 601-move job then lost 152 frames.  A real arm at
115200 read at 9600 sends the host noise, and ``armctl`` says to check the baud rate, sending
nothing: the simulator does the same now.
"""
from __future__ import annotations

import subprocess
import sys

import pytest
import serial

import armctl.sim  # noqa: F401  (registers sim://)
from armctl import Arm
from armctl.core.frame_fields import STATUS_HEAD
from armctl.errors import ArmctlError

pytestmark = pytest.mark.timeout(30)

JOB = "G1 X250 Y0 Z150 A180 B0 C0 F3000 S1000\n"


@pytest.mark.parametrize("url, host_baud", [("sim://?clock=virtual&baud=115200", 9600),
                                            ("sim://?clock=virtual&baud=9600", 115200),
                                            ("sim://?baud=115200&speed=8", 9600)])
def test_a_port_at_another_rate_than_the_arm_hears_only_noise_and_the_arm_nothing(url, host_baud):
    port = serial.serial_for_url(url, baudrate=host_baud, timeout=0)
    try:
        assert port.baudrate == host_baud  # the port's own rate, as any pyserial port keeps it
        heard = bytearray()
        for _ in range(40):
            port.write(bytes(48))
            if port.virtual_clock is not None:
                port.virtual_clock.advance_to(port.virtual_clock.now_s + 0.05)
            else:
                import time
                time.sleep(0.01)
            heard += port.read(4096)
        assert heard, "the line was silent: an arm at another rate still sends (noise)"
        assert STATUS_HEAD not in heard, "a status frame can start in the noise"
        assert port.model.frames_received == [], "the arm took frames sent at another rate"
    finally:
        port.close()


def test_the_same_rate_on_both_ends_is_a_clean_line():
    port = serial.serial_for_url("sim://?clock=virtual&baud=115200", baudrate=115200, timeout=0)
    try:
        port.virtual_clock.advance_to(0.5)
        assert STATUS_HEAD in port.read(4096)
    finally:
        port.close()


def test_run_without_baud_on_a_115200_arm_says_to_check_the_rate_and_sends_nothing(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    result = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--no-live", "--port",
                             "sim://?clock=virtual&baud=115200"], capture_output=True, text=True, timeout=25,
                            env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "XDG_DATA_HOME": str(tmp_path / "d")},
                            cwd=tmp_path)
    assert result.returncode == 1, result
    assert "never formed a status frame" in result.stderr and "is the baud rate right?" in result.stderr, result.stderr
    assert "nothing was sent" in result.stderr and "Traceback" not in result.stderr


def test_the_api_with_the_arms_rate_runs_the_job(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    with Arm.open("sim://?clock=virtual&baud=115200", 115200) as arm:
        assert arm.run(str(script)).outcome == "finished"
    with Arm.open("sim://?clock=virtual&baud=115200") as arm, pytest.raises(ArmctlError):
        arm.run(str(script))


def test_setting_the_port_to_the_arms_rate_once_open_cleans_the_line():
    port = serial.serial_for_url("sim://?clock=virtual&baud=115200", baudrate=9600, timeout=0)
    try:
        port.virtual_clock.advance_to(0.3)
        assert STATUS_HEAD not in port.read(4096)
        port.baudrate = 115200
        port.virtual_clock.advance_to(0.6)
        assert STATUS_HEAD in port.read(4096)
    finally:
        port.close()
