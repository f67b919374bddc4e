"""Review 8: ``armctl status --watch``'s live panel redrew itself whole, 12 times a second (rich's
``Live``): on a 120 × 40 pseudo-terminal (``script``, the installed command, ``sim://``) 319,591 and
328,409 bytes in 10 s.  What changes on an arm at rest is two lines — the kinds' ages and the
link's counts — and they are what a person needs at least 10 times a second; the panel now writes
the lines that changed (armctl/ui/live_lines.py, as ``armctl run``'s panel does).

The installed command in a fresh process on a pseudo-terminal of 120 × 40, for 3 s of wall time
after the panel first shows: a budget of bytes (fewer refreshes on a loaded machine write fewer).
"""

from __future__ import annotations

import fcntl
import os
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}
WATCH_S = 3.0
FIRST_PANEL_BYTES = 4000  # the panel whole, once: 15 lines of 120 columns with their styles (~3 KB)
# then at most 12 refreshes a second of the lines that change — an arm at rest: the ages and the link's
# counts; allowed three lines of ~160 bytes each: 5.8 KB a second (before: ~32 KB a second)
BYTES_PER_S = 12 * 3 * 160


def _watched(seconds: float) -> bytes:
    """What ``armctl status --watch`` wrote to a 120 × 40 terminal in ``seconds`` after its panel showed."""
    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    try:
        process = subprocess.Popen([sys.executable, "-m", "armctl", "status", "--watch", "--port", "sim://"],
                                   stdin=slave, stdout=slave, stderr=slave, cwd=ROOT,
                                   preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                                   env={**ENV, "TERM": "xterm-256color", "COLUMNS": "120", "LINES": "40"})
    finally:
        os.close(slave)
    output, shown_at = b"", None
    try:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and (shown_at is None or time.monotonic() < shown_at + seconds):
            if select.select([master], [], [], 0.05)[0]:
                output += os.read(master, 65536)
            if shown_at is None and b"\xe2\x95\xaf" in output:  # the panel's last corner: drawn whole once
                shown_at, output = time.monotonic(), output[output.index(b"armctl status"):]
        assert shown_at is not None, output[-500:]
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20) == 130
    finally:
        process.kill()
        os.close(master)
    return output


@pytest.mark.realtime
@pytest.mark.timeout(60)
def test_the_watch_panel_writes_the_lines_that_change():
    output = _watched(WATCH_S)
    assert len(output) <= FIRST_PANEL_BYTES + BYTES_PER_S * WATCH_S, len(output)
    redraws = len(re.findall(rb"\x1b\[\d+A", output))  # each refresh that changed a line moves the cursor up once
    assert redraws >= 5 * WATCH_S, redraws  # (12 a second asked; a shared machine's scheduling allowed for)
    assert b"status frames/s" in output and b"bytes read" in output


def test_the_watch_panel_refreshes_at_least_10_times_a_second():
    from armctl.ui.status_watch import WATCH_REFRESH_S

    assert WATCH_REFRESH_S <= 0.1
