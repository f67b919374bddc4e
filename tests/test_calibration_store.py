"""Issue 24 item 1, the store itself (armctl/host/calibration.py): an arm's identity from its port,
one record per arm in the user data directory, written atomically, a later probe laid over an
earlier one, list and forget; and the profile that lays a stored calibration over its own
``[connector]`` for the arm on the port, and only for that arm."""

from __future__ import annotations

import json
import os
from pathlib import Path
from types import SimpleNamespace

import pytest

from armctl.host import calibration
from armctl.host.calibration import Calibration, Measured, arm_identity, arm_profile
from armctl.errors import ConfigError, ProfileError
from armctl.host.profile import DOCUMENT, load_profile

pytestmark = pytest.mark.timeout(30)


def _usb(device, vid=0x0403, pid=0x6001, serial="A10K4XYZ", location="1-1.2:1.0"):
    return SimpleNamespace(device=device, vid=vid, pid=pid, serial_number=serial, location=location)


# --- identity ----------------------------------------------------------------------------------


@pytest.mark.parametrize("url", [
    "sim://?fifo_frames=50&speed_factor=1.3",
    "sim://?speed_factor=1.3&fifo_frames=50",
    "sim://?clock=virtual&fifo=50&slowdown=1.30",  # aliases, another spelling of the number, the clock
    "sim://?speed=4&fifo_frames=50&speed_factor=1.3&seed=7&loss=0.05",  # time scale, seed, faults: not the arm
    "sim://?fifo_frames=50&speed_factor=1.3&control_frames=queued&status_xyz_frame=worktable&link_scale=1",
])
def test_every_spelling_of_one_simulated_arm_is_one_identity(url):
    assert arm_identity(url) == "sim://?fifo_frames=50&speed_factor=1.3"


def test_the_arm_options_are_the_identity_of_a_simulated_arm(tmp_path):
    assert arm_identity("sim://") == arm_identity("sim://?clock=virtual") == "sim://"
    assert arm_identity("sim://?fifo_frames=200") == "sim://"  # the default FIFO: the same arm
    assert arm_identity("sim://?fifo_frames=50") != arm_identity("sim://?fifo_frames=51")
    for option in ("control_frames=arrival", "status_xyz_frame=robot", "link_scale=1.05", "baud=115200",
                   "status_jitter_ms=3"):  # (a jittery arm's probe allows for it: not the exact arm's results)
        assert arm_identity(f"sim://?{option}") == f"sim://?{option}"
    profile = tmp_path / "arm.toml"
    profile.write_text("")
    assert arm_identity(f"sim://?profile={profile}") == f"sim://?profile={profile}"


def test_a_network_arm_is_its_host_and_port():
    assert arm_identity("socket://Arm.local:4001") == "socket://arm.local:4001"
    assert arm_identity("socket://arm.local:4001?logging=debug") == "socket://arm.local:4001"
    assert arm_identity("rfc2217://10.0.0.5:2217") == "rfc2217://10.0.0.5:2217"
    assert arm_identity("socket://arm.local:4001") != arm_identity("rfc2217://arm.local:4001")


def test_a_usb_arm_is_its_vid_pid_and_serial_number_wherever_it_is_plugged_in(tmp_path):
    link = tmp_path / "usb-FTDI_arm-if00-port0"
    link.symlink_to("/dev/ttyUSB0")  # /dev/serial/by-id/… names the same device
    ports = [_usb("/dev/ttyUSB0"), _usb("/dev/ttyUSB1", serial="B2")]
    assert arm_identity("/dev/ttyUSB0", ports) == "usb 0403:6001 serial A10K4XYZ"
    assert arm_identity(str(link), ports) == "usb 0403:6001 serial A10K4XYZ"
    assert arm_identity("/dev/ttyUSB1", ports) == "usb 0403:6001 serial B2"  # another arm on the next port
    moved = [_usb("/dev/ttyUSB3")]
    assert arm_identity("/dev/ttyUSB3", moved) == arm_identity("/dev/ttyUSB0", ports)  # plugged in elsewhere


def test_a_device_without_a_serial_number_is_its_usb_location_or_its_path():
    assert arm_identity("/dev/ttyACM0", [_usb("/dev/ttyACM0", serial=None)]) == "usb 0403:6001 at 1-1.2:1.0"
    assert arm_identity("/dev/ttyS0", [_usb("/dev/ttyS0", vid=None, pid=None)]) == "device /dev/ttyS0"
    assert arm_identity("/dev/pts/7", []) == "device /dev/pts/7"
    assert arm_identity("COM3", [_usb("COM3", serial="W1")]) == "usb 0403:6001 serial W1"  # Windows
    assert arm_identity("COM4", []) == "device COM4"  # not a file here: as named, whatever the directory


def test_an_identity_is_its_own_identity():
    for arm in ("usb 0403:6001 serial A10K4XYZ", "device /dev/ttyS0", "sim://?fifo_frames=50"):
        assert arm_identity(arm) == arm


def test_a_bad_sim_url_is_a_config_error():
    with pytest.raises(ConfigError, match="unknown option"):
        arm_identity("sim://?fifo_frame=50")


# --- the store ---------------------------------------------------------------------------------


def _record(arm="sim://?fifo_frames=50", date="2026-11-01", **values) -> Calibration:
    values = values or {"fifo_frames": 50, "speed_factor": 1.3}
    return Calibration(arm, arm, {k: Measured(v, date, f"evidence of {k}", "sure") for k, v in values.items()})


def test_the_store_is_in_the_user_data_directory_xdg_data_home(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    path = calibration.save(_record())
    assert path.parent == tmp_path / "armctl" / "arms"
    assert calibration.load("sim://?fifo_frames=50") == _record()


@pytest.mark.parametrize("value", [None, "", "relative/dir", "/tmp/armctl-xdg-data"])
def test_the_data_directory_is_where_platformdirs_puts_it(monkeypatch, value):
    platformdirs = pytest.importorskip("platformdirs")
    if value is None:
        monkeypatch.delenv("XDG_DATA_HOME", raising=False)
    else:
        monkeypatch.setenv("XDG_DATA_HOME", value)
    assert calibration.data_dir() == Path(platformdirs.user_data_dir("armctl", appauthor=False))


def test_a_later_probe_replaces_what_it_measured_and_keeps_the_rest(tmp_path):
    calibration.save(_record(date="2026-11-01", fifo_frames=50, speed_factor=1.3), tmp_path)
    calibration.save(_record(date="2026-11-20", fifo_frames=48), tmp_path)  # a --no-motion probe: no speed factor
    record = calibration.load("sim://?fifo_frames=50", tmp_path)
    assert record.values() == {"fifo_frames": 48, "speed_factor": 1.3}
    assert record.source_of("fifo_frames") == "probed on 2026-11-20 for sim://?fifo_frames=50"
    assert record.source_of("speed_factor") == "probed on 2026-11-01 for sim://?fifo_frames=50"


def test_the_record_is_written_atomically_and_leaves_no_temporary_file(tmp_path, monkeypatch):
    calibration.save(_record(), tmp_path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def crash(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", crash)
    with pytest.raises(ConfigError, match="No space left"):
        calibration.save(_record(fifo_frames=7), tmp_path)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # the old record, whole; nothing else


def test_list_and_forget(tmp_path):
    assert calibration.stored(tmp_path / "none") == []
    calibration.save(_record("sim://?fifo_frames=50"), tmp_path)
    calibration.save(_record("usb 0403:6001 serial A1"), tmp_path)
    assert [c.arm for c in calibration.stored(tmp_path)] == ["sim://?fifo_frames=50", "usb 0403:6001 serial A1"]
    assert calibration.forget("usb 0403:6001 serial A1", tmp_path)
    assert not calibration.forget("usb 0403:6001 serial A1", tmp_path)
    assert [c.arm for c in calibration.stored(tmp_path)] == ["sim://?fifo_frames=50"]


@pytest.mark.parametrize("content", [b"not json", b"\xff\xfe", b"[]", b'{"format": 99}',
                                     b'{"format": 1, "arm": "x", "port": "x", "settings": {"fifo_frames": {"v": 1}}}'])
def test_a_damaged_record_is_a_config_error_naming_the_file(tmp_path, content):
    calibration.record_path("sim://?fifo_frames=50", tmp_path).parent.mkdir(parents=True, exist_ok=True)
    path = calibration.record_path("sim://?fifo_frames=50", tmp_path)
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=str(path)):
        calibration.load("sim://?fifo_frames=50", tmp_path)


# --- the profile of the arm on the port ---------------------------------------------------------


def test_the_stored_calibration_applies_to_its_arm_only(tmp_path):
    arm = "sim://?fifo_frames=50&speed_factor=1.3"
    calibration.save(_record(arm, date="2026-11-01", fifo_frames=50, speed_factor=1.3))
    mine = arm_profile(start=tmp_path, port="sim://?clock=virtual&speed_factor=1.3&fifo_frames=50")
    assert (mine.connector.fifo_frames, mine.connector.speed_factor) == (50, 1.3)
    assert mine.source_of("connector.fifo_frames") == f"probed on 2026-11-01 for {arm}"
    assert arm_profile(start=tmp_path, port="sim://?fifo_frames=50").connector.speed_factor == 1.0  # another arm
    assert not mine.connector.is_default("fifo_frames")  # a measured FIFO: ``done`` can be proven
    other = arm_profile(start=tmp_path, port="sim://?clock=virtual")
    assert (other.connector.fifo_frames, other.connector.speed_factor) == (200, 1.0)
    assert other.source_of("connector.fifo_frames") == DOCUMENT


def test_a_connector_table_measured_on_an_arm_applies_on_that_arm_only(tmp_path):
    (tmp_path / "armctl.toml").write_text('[connector]\nmeasured_on = "sim://?fifo_frames=50&speed_factor=1.3"\n'
                                          "fifo_frames = 50\nspeed_factor = 1.3\n")
    there = arm_profile(start=tmp_path, port="sim://?speed_factor=1.3&fifo=50&clock=virtual")
    assert there.connector.fifo_frames == 50 and there.source_of("connector.fifo_frames") == str(tmp_path / "armctl.toml")
    elsewhere = arm_profile(start=tmp_path, port="sim://?clock=virtual")
    assert elsewhere.connector.fifo_frames == 200 and elsewhere.source_of("connector.fifo_frames") == DOCUMENT


def test_a_connector_table_that_names_no_arm_applies_on_every_port(tmp_path):
    (tmp_path / "armctl.toml").write_text("[connector]\nfifo_frames = 120\n")
    for port in ("sim://", "sim://?fifo_frames=50", "socket://arm:4001"):
        assert arm_profile(start=tmp_path, port=port).connector.fifo_frames == 120


def test_the_project_file_wins_over_the_store_key_by_key(tmp_path):
    calibration.save(_record(fifo_frames=50, speed_factor=1.3))
    (tmp_path / "armctl.toml").write_text('[connector]\nmeasured_on = "sim://?fifo_frames=50"\nspeed_factor = 1.25\n')
    profile = arm_profile(start=tmp_path, port="sim://?fifo_frames=50")
    assert (profile.connector.fifo_frames, profile.connector.speed_factor) == (50, 1.25)
    assert profile.source_of("connector.fifo_frames").startswith("probed on ")
    assert profile.source_of("connector.speed_factor") == str(tmp_path / "armctl.toml")


def test_without_a_port_the_configured_ports_calibration_applies(tmp_path, monkeypatch):
    """lint, estimate and plot open no port: the one they would use decides."""
    calibration.save(_record(fifo_frames=50, speed_factor=1.3))
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "armctl.toml").write_text('port = "sim://?fifo_frames=50&clock=virtual"\n')
    assert arm_profile(start=tmp_path).connector.speed_factor == 1.3
    monkeypatch.setenv("ARMCTL_PORT", "sim://")
    assert arm_profile(start=tmp_path).connector.speed_factor == 1.0


@pytest.mark.parametrize("table, message", [
    ("measured_on = 5\nfifo_frames = 50\n", "connector.measured_on must be the port"),
    ('measured_on = "sim://?fifo_frame=5"\n', "connector.measured_on: unknown option"),
    ('measured_on = "sim://?fifo_frames=7"\nfifo_frame = 50\n', "unknown key 'connector.fifo_frame'"),
])
def test_a_bad_connector_table_is_refused_whatever_arm_it_names(tmp_path, table, message):
    (tmp_path / "armctl.toml").write_text("[connector]\n" + table)
    with pytest.raises((ConfigError, ProfileError), match=message):
        arm_profile(start=tmp_path, port="sim://")


def test_a_damaged_stored_value_is_refused_naming_its_source(tmp_path):
    calibration.save(_record(fifo_frames=0))
    with pytest.raises(ProfileError, match="probed on 2026-11-01 for sim://.fifo_frames=50: connector.fifo_frames"):
        arm_profile(start=tmp_path, port="sim://?fifo_frames=50")


def test_the_record_is_json_a_person_can_read():
    path = calibration.save(_record())
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["arm"] == "sim://?fifo_frames=50" and data["format"] == 1
    assert data["settings"]["fifo_frames"] == {"value": 50, "probed_on": "2026-11-01",
                                               "evidence": "evidence of fifo_frames", "confidence": "sure"}


def test_the_portless_profile_takes_only_a_connector_table_that_names_no_arm(tmp_path):
    """``armctl.host.profile.load_profile`` knows no port (the simulated arm's own profile, a library
    reading a profile): a table measured on an arm is not its, one written by hand is."""
    calibration.save(_record(fifo_frames=50))
    (tmp_path / "armctl.toml").write_text('[connector]\nmeasured_on = "sim://"\nfifo_frames = 50\n')
    assert load_profile(start=tmp_path).connector.fifo_frames == 200
    (tmp_path / "armctl.toml").write_text("[connector]\nfifo_frames = 60\n")
    assert load_profile(start=tmp_path).connector.fifo_frames == 60
