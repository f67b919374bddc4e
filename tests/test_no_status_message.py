"""A port that never completes the status says why the same way in every command and in the API:
nothing heard (power, cable), bytes that never formed a status frame (the baud rate: an arm at
115200 read at 9600 sends just that), or the kinds never seen — and a job adds that nothing was
sent.  ``armctl status`` said "is the baud rate right?"; ``armctl run`` and ``Arm.status()`` only
counted the bytes, so a user at the wrong rate got no hint from the command they ran first.
"""
from __future__ import annotations

import subprocess
import sys

import pytest

from armctl import Arm
from armctl.errors import ArmctlError

from test_cli_status import tcp_peer

pytestmark = pytest.mark.timeout(30)

JUNK = bytes(range(0x20, 0x60))  # no 0xCE anywhere: never a status frame
JOB = "G1 X250 Y0 Z150 A180 B0 C0 F3000 S1000\n"


def test_run_at_the_wrong_rate_says_to_check_the_baud_rate_and_sends_nothing(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    with tcp_peer(JUNK) as url:
        result = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", url, "--timeout", "0.3",
                                 "--no-live"], capture_output=True, text=True, timeout=20)
    assert result.returncode == 1, result
    message = result.stderr.strip()
    assert message.startswith(f"armctl: no complete status from {url} at 9600 baud within 0.3 s: received "), message
    assert "bytes that never formed a status frame" in message and "is the baud rate right?" in message, message
    assert message.endswith("nothing was sent"), message
    assert "Traceback" not in result.stderr


def test_the_api_says_the_same(tmp_path):
    with tcp_peer(JUNK) as url, Arm.open(port=url) as arm:
        with pytest.raises(ArmctlError) as raised:
            arm.status(timeout=0.3)
    assert "never formed a status frame" in str(raised.value) and "is the baud rate right?" in str(raised.value)
