"""Every command prints anything on any output encoding: an ordinary finding (…, →, °), a
decoded frame (µs, mm/s²) or a user's own text never raises UnicodeEncodeError.

Issue 10: with PYTHONIOENCODING=latin-1 a plain lint finding crashed.  The fix is one
mechanism at the entry point (cli.ArmctlGroup.main), so the test goes through the installed
command in a fresh process, where the real stdout encoding applies.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from armctl.core.protocol import AccelLinearMove

# A comment with characters no 8-bit code page holds, a finding whose message has …,
# and (through decode/dry-run) units with µ and ².
SCRIPT = "G1 X200 Y0 Z150 A180 B0 C0 F3000 S1500 ; 日本 → … °\nG1 S9999 ; →\n"
ARGUMENTS = [
    (["lint"], 1),
    (["compile"], 1),
    (["lint", "--format", "json"], 1),
]


def _run(arguments, encoding, **kwargs):
    env = {**os.environ, "PYTHONIOENCODING": encoding}
    return subprocess.run([sys.executable, "-m", "armctl", *arguments], capture_output=True, env=env,
                          timeout=60, **kwargs)


@pytest.mark.parametrize("encoding", ["latin-1", "ascii"])
@pytest.mark.parametrize("arguments, code", ARGUMENTS, ids=lambda a: " ".join(a) if isinstance(a, list) else None)
def test_findings_print_on_a_narrow_encoding(tmp_path, encoding, arguments, code):
    script = tmp_path / "ünïcode→.txt"
    script.write_text(SCRIPT, encoding="utf-8")
    done = _run([*arguments, str(script)], encoding)
    out = (done.stdout + done.stderr).decode("utf-8", "replace")
    assert "Traceback" not in out and "UnicodeEncodeError" not in out, out
    assert done.returncode == code, out
    assert "E005" in out and "9999" in out


@pytest.mark.parametrize("encoding", ["latin-1", "ascii"])
def test_decode_and_dry_run_print_units_on_a_narrow_encoding(tmp_path, encoding):
    frame = AccelLinearMove(1, 200, 0, 150, 180, 0, 0, accel_mm_s2=800, speed1_mm_min=2000).encode()
    done = _run(["decode", "-"], encoding, input=frame.hex().encode())
    out = (done.stdout + done.stderr).decode("utf-8", "replace")
    assert done.returncode == 0 and "Traceback" not in out, out
    assert "accel=800 mm/s" in out
    script = tmp_path / "ok.txt"
    script.write_text("G1 X200 Y0 Z150 A180 B0 C0 F3000 S1500 ; → …\n", encoding="utf-8")
    done = _run(["run", "--dry-run", str(script)], encoding)
    out = (done.stdout + done.stderr).decode("utf-8", "replace")
    assert done.returncode == 0 and "Traceback" not in out, out
    assert "pwm=1500" in out
