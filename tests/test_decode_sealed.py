"""``armctl decode`` of a ``run --log`` checks each sealed record's CRC-32.  Found by the crash
review: one flipped bit in a tx record's hex showed "y=2.2e-44 mm", a frame never sent, with
exit 0 and no warning.  Now a record whose checksum does not match shows no bytes, and decode
says which line it was and exits 1 (problems); a log without seals (hand-made, or format 1)
decodes as before, and the crash's torn last line is no damage.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.core.joblog import seal
from armctl.core.protocol import LinearMove
from armctl.ui.cli import main

pytestmark = pytest.mark.timeout(60)

ARMCTL = Path(sys.executable).with_name("armctl")


def _log(tmp_path, flip: bool, torn: str = "") -> Path:
    frame = LinearMove(250.0, -50.0, 150.0, 180.0, 0.0, 0.0, 1000.0, 3000.0).encode().hex()
    records = [{"t": 0.1, "dir": "tx", "hex": frame, "line": 1}, {"t": 0.13, "dir": "rx", "hex": "ce083400000bb800cf"}]
    lines = [seal(r, seq) for seq, r in enumerate(records)]
    if flip:  # one bit of the frame's hex: a digit still, the checksum no longer matches
        at = lines[0].index('"hex": "') + 8 + 30
        digit = lines[0][at]
        lines[0] = lines[0][:at] + format(int(digit, 16) ^ 1, "x") + lines[0][at + 1:]
    path = tmp_path / "run.log"
    path.write_text("\n".join(lines) + "\n" + torn)
    return path


def test_a_damaged_record_shows_no_bytes_and_exits_1(tmp_path):
    """Nor does any record after it (tests/test_decode_prefix.py: only the intact prefix is trusted)."""
    result = CliRunner().invoke(main, ["decode", str(_log(tmp_path, flip=True))])
    assert result.exit_code == 1, result.output
    assert ("run.log:1: a damaged record (its checksum does not match): the log is decoded up to it; it and the "
            "1 line(s) after it are not shown") in result.output
    assert "0 command frame(s), 0 status frame(s)" in result.output


def test_an_intact_log_and_its_torn_last_line_decode_as_before(tmp_path):
    result = CliRunner().invoke(main, ["decode", str(_log(tmp_path, flip=False, torn='{"t": 0.2, "dir": "tx", "he'))])
    assert result.exit_code == 0, result.output
    assert "1 command frame(s), 1 status frame(s)" in result.output and "damaged" not in result.output


def test_the_installed_command(tmp_path):
    done = subprocess.run([str(ARMCTL), "decode", "--json", str(_log(tmp_path, flip=True))], capture_output=True,
                          text=True, timeout=50)
    assert done.returncode == 1 and "a damaged record" in done.stderr and "Traceback" not in done.stderr
    assert '"direction": "tx"' not in done.stdout, done.stdout


def test_a_bit_flipped_in_a_records_key_is_damage_too(tmp_path):
    """Found by the README audit (wt-readme): one bit of a tx record's ``"hex"`` key flipped
    (``"hdx"``) dropped the frame with exit 0 and no word — a record with no ``hex`` carried no
    bytes, before its checksum was looked at.  A sealed record whose checksum does not match is
    damage whatever part of it the damage hit (README: its line is named, exit 1)."""
    path = _log(tmp_path, flip=False)
    lines = path.read_text().splitlines()
    assert '"hex": ' in lines[0]
    lines[0] = lines[0].replace('"hex": ', '"hdx": ', 1)  # 'e' ^ 1 == 'd': one bit
    path.write_text("\n".join(lines) + "\n")
    result = CliRunner().invoke(main, ["decode", str(path)])
    assert result.exit_code == 1, result.output
    assert "run.log:1: a damaged record (its checksum does not match)" in result.output
