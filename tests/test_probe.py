"""armctl probe: every setting recovered exactly from the simulator in each variant, in virtual
time; safe (no motion without consent, restore on Ctrl-C); JSON, --write, wrong encodings.

Most tests drive the pure probe over a Link to ``sim://?clock=virtual`` in-process (a probe
takes well under a second there); a few go through click's CliRunner and the installed command
in a fresh process.  "Arm time" is the probe's own virtual time, never the wall clock.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time

import pytest
from click.testing import CliRunner
from hypothesis import given, settings, strategies as st

from armctl.ui.cli import main
from armctl.host.link import Link
from armctl.probe import SETTINGS, build_probe
from armctl.probe.host import FrameInbox, drive
from armctl.probe.toml_edit import updated
from armctl.host.profile import load_profile
from armctl.core.protocol import JointMove, decode_command

VIRTUAL = "sim://?clock=virtual"
ARM_TIME_LIMIT_S = 180.0


class RecordingPort:
    """A sim:// port that remembers every frame written (and may rewrite them first)."""

    def __init__(self, port, rewrite=None) -> None:
        self._port, self._rewrite, self.written = port, rewrite, []

    def write(self, data):
        data = self._rewrite(data) if self._rewrite else data
        self.written.append(bytes(data))
        return self._port.write(data)

    def __getattr__(self, name):
        return getattr(self._port, name)


def probe_sim(options: str = "", motion: bool = False, rewrite=None, stop_when=None, profile=None, before=()):
    """Run the probe on ``sim://?clock=virtual&options``: (probe, the simulated arm, the port).
    ``before``: frames another program wrote just before the probe started."""
    import serial

    url = f"{VIRTUAL}&{options}" if options else VIRTUAL
    raw = serial.serial_for_url(url, baudrate=9600, timeout=0)
    for frame in before:
        raw.write(frame)
    port = RecordingPort(raw, rewrite)
    inbox = FrameInbox()
    link = Link(port, url, on_status=inbox)
    stop = threading.Event()

    def progress(probe):
        if stop_when is not None and stop_when(probe):
            stop.set()

    probe = build_probe(profile or load_profile(), 9600, link.clock(), motion, virtual_clock=True)
    drive(link, probe, inbox, progress, stop)
    return probe, port.model, port


def values(probe) -> dict:
    from armctl.probe.report import settings as found

    return found(probe)


def assert_as_found(model) -> None:
    assert model.origin_mm == (0.0, 0.0, 0.0)
    assert model.pwm_us == 1500.0
    assert not model.paused
    assert all(abs(a - b) < 1e-6 for a, b in zip(model.pose.joints, (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)))


# --- each setting, each variant -----------------------------------------------------------------


@pytest.mark.parametrize("fifo", [50, 120, 200, 250])
def test_fifo_exact_through_the_cli(fifo):
    result = CliRunner().invoke(main, ["probe", "--port", f"{VIRTUAL}&fifo={fifo}", "--no-motion", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["fifo_frames"] == fifo
    assert data["details"]["fifo_frames"]["confidence"] == "sure"
    assert data["details"]["arm_time_s"] <= ARM_TIME_LIMIT_S


@settings(max_examples=12, deadline=None)
@given(fifo=st.integers(50, 250), arrival=st.booleans())
def test_fifo_exact_for_any_size(fifo, arrival):
    control = "arrival" if arrival else "queued"
    probe, model, _ = probe_sim(f"fifo={fifo}&control={control}")
    assert values(probe)["fifo_frames"] == fifo
    assert values(probe)["control_frames"] == control
    assert_as_found(model)


@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_control_frames(control):
    probe, model, _ = probe_sim(f"control={control}")
    assert values(probe)["control_frames"] == control
    assert_as_found(model)


@pytest.mark.parametrize("slowdown", [0.7, 1.0, 1.3, 2.0])
def test_speed_factor_within_the_stated_precision(slowdown):
    probe, model, _ = probe_sim(f"slowdown={slowdown}&fifo=250", motion=True)
    found = probe.finding("speed_factor")
    assert found.confidence == "sure"
    assert abs(found.value - slowdown) <= found.details["precision"] <= 0.02
    assert values(probe)["kinematics_verified"] is True
    assert values(probe)["fifo_frames"] == 250
    assert probe.arm_time_s <= ARM_TIME_LIMIT_S  # the slowest arm, the largest FIFO, with motion
    assert_as_found(model)


def test_status_xyz_frame_worktable():
    probe, _, _ = probe_sim()
    assert values(probe)["status_xyz_frame"] == "worktable"



def test_status_xyz_frame_robot():
    probe, model, _ = probe_sim("status_xyz_frame=robot")
    assert values(probe)["status_xyz_frame"] == "robot"
    assert_as_found(model)


def test_status_stream_period_and_rotation():
    found = probe_sim()[0].finding("status_stream")
    assert found.details == {"period_ms": 30.0, "rotation": [0, 1, 2, 3, 4, 5, 100, 102, 103]}


def test_kinematics_that_differ_are_not_verified_and_no_linear_move(tmp_path):
    arm = tmp_path / "arm.toml"
    arm.write_text("[links]\nupper_arm_mm = 200.0\nforearm_mm = 170.0\n")
    probe, model, port = probe_sim(f"profile={arm}", motion=True)
    found = probe.finding("kinematics_verified")
    assert (found.value, found.confidence) == (False, "sure")
    assert "no linear move" in probe.finding("speed_factor").evidence
    sent = [decode_command(frame) for frame in port.written]
    assert not any(type(command).__name__ == "LinearMove" for command in sent)
    assert model.origin_mm == (0.0, 0.0, 0.0) and model.pwm_us == 1500.0


# --- safety -------------------------------------------------------------------------------------


def test_no_motion_sends_nothing_that_moves():
    probe, model, port = probe_sim(motion=False)
    start = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)
    kinds = set()
    for frame in port.written:
        command = decode_command(frame)
        kinds.add(type(command).__name__)
        if isinstance(command, JointMove):
            assert command.joints_deg == start  # PWM-only: to the joints the arm reports
    assert kinds <= {"Delay", "PauseToggle", "SetWorktableOrigin", "JointMove"}
    assert model.pose.joints == start
    assert values(probe)["speed_factor"] is None
    assert probe.finding("speed_factor") is None


@pytest.mark.parametrize("step, after_s", [("checking the encoding (G54)", 0.0),
                                           ("control frames (pause behind a delay)", 0.5),
                                           ("FIFO capacity", 8.0), ("speed factor (small moves)", 2.0)])
@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_ctrl_c_mid_probe_restores(step, after_s, control):
    started = {}

    def stop_when(probe):
        if probe.current == step:
            started.setdefault("s", probe.arm_time_s)
            return probe.arm_time_s >= started["s"] + after_s
        return False

    probe, model, _ = probe_sim(f"control={control}", motion=True, stop_when=stop_when)
    assert probe.interrupted
    assert_as_found(model)
    assert any(note.startswith("as found") for note in probe.notes)
    assert not any(note.startswith("NOT") for note in probe.notes)


@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_status_loss_and_corruption_never_claim_a_wrong_value(control):
    truth = {"fifo_frames": 120, "control_frames": control, "status_xyz_frame": "worktable", "kinematics_verified": True}
    stated = 0
    for seed in range(3):
        probe, model, _ = probe_sim(f"fifo=120&control={control}&slowdown=1.3&loss=0.05&corrupt=0.05&seed={seed}",
                                    motion=True)
        found = values(probe)
        for name, value in truth.items():
            assert found[name] in (value, None), (seed, name, found[name])
            stated += found[name] is not None
        if found["speed_factor"] is not None:
            assert abs(found["speed_factor"] - 1.3) <= probe.finding("speed_factor").details["precision"]
        assert_as_found(model)
    assert stated >= 3 * len(truth) - 2  # "unsure" is allowed, not as the rule


def test_a_moving_arm_is_left_alone():
    move = JointMove(30.0, 0.0, 0.0, 0.0, 90.0, 0.0, pwm_us=1500.0, speed_deg_s=5.0).encode()
    probe, model, port = probe_sim(before=[move])
    assert probe.stopped is not None and "moving" in str(probe.stopped)
    assert port.written == []  # nothing sent, nothing to restore


def test_a_paused_arm_is_left_alone():
    from armctl.core.protocol import PauseToggle

    probe, model, port = probe_sim(before=[PauseToggle().encode()])
    assert probe.stopped is not None and "paused" in str(probe.stopped)
    assert port.written == [] and model.paused


@pytest.mark.parametrize("got, hypothesis", [
    ((6553.6 - 123.4, 6553.6 - 56.7, 6553.6 - 28.9), "unsigned"),
    ((-12.3, -5.7, -2.9), "scale"),
    ((1.0, 2.0, 3.0), "H1) or the sign/scale"),
])
def test_diagnose_origin_names_the_hypothesis(got, hypothesis):
    from armctl.probe.steps import diagnose_origin

    message, _ = diagnose_origin((-123.4, -56.7, -28.9), got)
    assert hypothesis in message


# --- wrong encodings: stop, explain, put the origin back --------------------------------------


def _big_endian_floats(data: bytes) -> bytes:
    """What a big-endian arm would make of our frames, expressed as the bytes a little-endian
    one would read the same way: each float slot reversed."""
    frame = bytearray(data)
    if len(frame) == 48:
        for offset in range(3, 47, 4):
            frame[offset:offset + 4] = frame[offset:offset + 4][::-1]
    return bytes(frame)


def test_wrong_float_byte_order_stops_with_an_explanation():
    probe, model, _ = probe_sim(rewrite=_big_endian_floats)
    assert probe.stopped is not None and "H1 is wrong" in str(probe.stopped)
    assert model.origin_mm == (0.0, 0.0, 0.0)  # put back in the arm's own byte order
    assert probe.finding("fifo_frames") is None  # nothing else was tried


def test_wrong_encoding_exits_1_through_the_cli(monkeypatch):
    import armctl.probe.host as host

    original = host.drive

    def big_endian_drive(link, probe, inbox, progress=None, stop=None):
        link.port = RecordingPort(link.port, _big_endian_floats)
        return original(link, probe, inbox, progress, stop)

    monkeypatch.setattr(host, "drive", big_endian_drive)
    result = CliRunner().invoke(main, ["probe", "--port", VIRTUAL, "--no-motion"])
    assert result.exit_code == 1
    assert "H1 is wrong" in result.stderr


# --- output and --write -------------------------------------------------------------------------


def test_json_keys_exactly():
    result = CliRunner().invoke(main, ["probe", "--port", f"{VIRTUAL}&fifo=50", "--no-motion", "--json"])
    data = json.loads(result.stdout)
    assert set(data) == {*SETTINGS, "details"}
    assert data["details"]["restored"]


def test_write_creates_and_updates_keeping_the_rest(tmp_path):
    target = tmp_path / "armctl.toml"
    run = lambda *args: CliRunner().invoke(main, ["probe", "--port", f"{VIRTUAL}&fifo=50", "--no-motion", *args])
    result = run("--write", str(target))
    assert result.exit_code == 0, result.output
    assert "fifo_frames = 50" in target.read_text()
    target.write_text('# my arm\nbaud = 9600  # keep\n\n[connector]\nfifo_frames = 7  # old\n\n[jog]\nx = 1\n')
    result = run("--write", str(target))
    assert result.exit_code == 0, result.output
    text = target.read_text()
    assert text.startswith('# my arm\nbaud = 9600  # keep\n\n[connector]\nfifo_frames = 50  # old\n')
    assert 'control_frames = "queued"' in text and text.endswith("\n[jog]\nx = 1\n")


def test_write_refuses_a_file_that_is_not_toml(tmp_path):
    target = tmp_path / "armctl.toml"
    target.write_text("port = [\n")
    result = CliRunner().invoke(main, ["probe", "--port", VIRTUAL, "--no-motion", "--write", str(target)])
    assert result.exit_code == 2
    assert "not valid TOML" in result.stderr
    assert target.read_text() == "port = [\n"


def test_toml_edit_keeps_everything_else():
    text = "a = 1\n[connector]\n# c\nfifo_frames = 200\n\n# next\n[jog]\nb = 2\n"
    result = updated(text, {"fifo_frames": 50, "speed_factor": 1.25})
    assert result == "a = 1\n[connector]\n# c\nfifo_frames = 50\nspeed_factor = 1.25\n\n# next\n[jog]\nb = 2\n"
    assert updated("", {"control_frames": "arrival"}) == '[connector]\ncontrol_frames = "arrival"\n'


# --- the installed command, in a fresh process --------------------------------------------------


def test_installed_command_reports_each_setting():
    completed = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", f"{VIRTUAL}&fifo=50&control=arrival",
                                "--json", "--yes"], capture_output=True, text=True, timeout=60)
    assert completed.returncode == 0, completed.stderr
    data = json.loads(completed.stdout)
    assert (data["fifo_frames"], data["control_frames"], data["status_xyz_frame"]) == (50, "arrival", "worktable")
    assert abs(data["speed_factor"] - 1.0) <= data["details"]["speed_factor"]["data"]["precision"]
    assert data["kinematics_verified"] is True


def test_no_terminal_and_no_yes_means_no_motion():
    completed = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", VIRTUAL, "--json"],
                               capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert completed.returncode == 0, completed.stderr
    assert "probing without motion" in completed.stderr
    assert json.loads(completed.stdout)["speed_factor"] is None


@pytest.mark.realtime
def test_sigint_restores_then_exits_130():
    process = subprocess.Popen([sys.executable, "-m", "armctl", "probe", "--port", "sim://?speed=5", "--no-motion"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for line in process.stdout:  # wait until the FIFO rounds run (the arm is busy, its FIFO full)
            if "FIFO capacity" in line:
                break
        time.sleep(0.3)
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130, err
    assert "as found: worktable origin, PWM, running (not paused), joints" in out


def test_an_arm_that_sends_no_status_gets_nothing_sent():
    """The pure core alone: no frames fed, time passing; it stops, having asked to write nothing."""
    from armctl.probe.plan import Wait

    probe = build_probe(load_profile(), 9600, 0.0, motion=True, virtual_clock=True)
    now_s, writes = 0.0, 0
    while (action := probe.next_action(now_s)) is not None:
        if isinstance(action, Wait):
            now_s = max(now_s + 0.01, action.until_s)
        else:
            writes += 1
    assert writes == 0
    assert "did not show its pose" in str(probe.stopped)


@pytest.mark.parametrize("target", ["/dev/full", "big.toml"])
def test_write_refuses_a_device_or_an_endless_file_before_anything_is_sent(tmp_path, target):
    """--write replaces its file: a device must never be replaced, and reading it (/dev/full gives
    zeros without end) must not hang; an armctl.toml is read bounded (1 MiB) like every other."""
    if target == "big.toml":
        (tmp_path / target).write_bytes(b"#" * (2 * 1024 * 1024))
    done = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", VIRTUAL, "--no-motion", "--write", target],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert ("not a regular file" if target == "/dev/full" else "longer than 1 MiB") in done.stderr
    assert "Traceback" not in done.stderr
    assert "listening to the status" not in done.stdout + done.stderr  # refused before the probe's first step
