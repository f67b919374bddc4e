"""Start-up: what a command does not use is not built (issue 13).  Fresh processes, since an
in-process test would see whatever earlier tests already imported."""

from __future__ import annotations

import subprocess
import sys

COMPILE_ONLY = """
import armctl.protocol as protocol
from armctl.script import compile_lines
job = compile_lines(iter(["G1 X200 Y0 Z150 A180 B0 C0 F3000 S1000", "G4 P10", "PAUSE"]), "job.txt")
assert len(list(job)) == 3 and job.error_count == 0
print("STATUS_KINDS" in vars(protocol))
"""

FIRST_USE = """
import armctl.protocol as protocol
frame = bytes([0xCE, 0x07, 0xD0, 0x00, 0x00, 0x05, 0xDC, 0x00, 0xCF])
assert protocol.is_status_frame(frame)  # defines the status classes on its own
status = protocol.decode_status(frame)
from armctl.protocol import PositionStatus
assert type(status) is PositionStatus and status == PositionStatus(200.0, 0.0, 150.0), status
assert type(status).__qualname__ == "PositionStatus" and repr(status).startswith("PositionStatus(")
assert protocol.STATUS_KINDS[0] is PositionStatus
try:
    protocol.NoSuchName
except AttributeError as error:
    assert "NoSuchName" in str(error)
else:
    raise SystemExit("a missing name must raise AttributeError")
print("ok")
"""


def _run(code: str) -> str:
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_compiling_a_script_builds_no_status_frame_class():
    assert _run(COMPILE_ONLY) == "False"


def test_the_status_classes_are_built_on_first_use_and_are_the_same_classes():
    assert _run(FIRST_USE) == "ok"
