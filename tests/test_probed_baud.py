"""A probed arm needs only ``--port``, its line rate included.  Found by the probe review: an arm
at 115200 baud, probed with ``--baud 115200``, still needed ``--baud 115200`` on every command
after it — the probe kept the arm's [connector] but not the rate it had read the arm's status at,
so "probe once, change --port and nothing else" did not hold for it.  Now the probe keeps the
rate with the arm (``calibration.Calibration.baud``), and every port-using command takes it when
neither ``--baud`` nor armctl.toml's ``baud`` says otherwise (``link.line_baud``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from armctl.host import calibration
from armctl.host.link import line_baud
from armctl.host.profile import load_config

pytestmark = pytest.mark.timeout(60)

ARMCTL = Path(sys.executable).with_name("armctl")
URL = "sim://?clock=virtual&baud=115200"


def _armctl(*words, cwd, env):
    return subprocess.run([str(ARMCTL), *words], cwd=cwd, env=env, capture_output=True, text=True, timeout=50)


def test_the_probe_keeps_the_line_rate_and_commands_take_it(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    probed = _armctl("probe", "--port", URL, "--baud", "115200", "--no-motion", cwd=tmp_path, env=env)
    assert probed.returncode == 0, probed.stdout + probed.stderr
    shown = json.loads(_armctl("config", "--port", URL, "--json", cwd=tmp_path, env=env).stdout)
    baud = shown["settings"]["baud"]
    assert baud["value"] == 115200 and baud["source"] == "probe", shown
    assert baud["where"].startswith("probed on ") and baud["where"].endswith("for sim://?baud=115200")
    # armctl.toml's baud, and --baud, still say otherwise when given
    (tmp_path / "armctl.toml").write_text("baud = 57600\n")
    shown = json.loads(_armctl("config", "--port", URL, "--json", cwd=tmp_path, env=env).stdout)
    baud = shown["settings"]["baud"]
    assert baud["value"] == 57600 and baud["source"] == "project", shown


def test_line_baud_prefers_the_option_then_the_file_then_the_probe(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.chdir(tmp_path)
    arm = calibration.arm_identity(URL)
    calibration.save(calibration.calibration_of(URL, arm, [], "2026-11-28", 115200))
    config = load_config()
    assert line_baud(None, config, URL) == (115200, f"probed on 2026-11-28 for {arm}")
    assert line_baud(19200, config, URL) == (19200, "--baud")
    assert line_baud(None, config, "sim://?clock=virtual")[0] == 9600  # another arm: the document's rate
    (tmp_path / "armctl.toml").write_text("baud = 57600\n")
    assert line_baud(None, load_config(), URL)[0] == 57600


def test_a_record_from_before_has_no_rate_and_still_loads(tmp_path):
    record = calibration.calibration_of("sim://", "sim://", [("fifo_frames", 200, "measured", "sure")], "2026-11-01")
    data = record.to_json()
    assert "baud" not in data
    again = calibration.Calibration.from_json(data, "old.json")
    assert again.baud is None and again.settings["fifo_frames"].value == 200
    with pytest.raises(Exception, match="baud"):
        calibration.Calibration.from_json({**data, "baud": "fast"}, "bad.json")
