"""``armctl status`` and ``armctl ports`` as a user sees them.

Every command runs through ``CliRunner`` in an empty working directory (no armctl.toml) with
``ARMCTL_PORT`` cleared, against the simulator (``sim://?clock=virtual``: model time moves only while
status waits), pyserial's ``loop://`` (which sends nothing), small TCP peers that send junk, and the
simulator's own pty and TCP bridges running in a thread.  ``--watch`` is tested on its line
loop with a fake link and a virtual clock, and once end to end in a subprocess with Ctrl-C.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import types

import pytest
from click.testing import CliRunner

from armctl.core.armstate import ArmState
from armctl.ui.cli import main
from armctl.errors import PortError
from armctl.host.profile import find_config
from armctl.core.protocol import FileLengthStatus, JointsLowStatus, PauseStatus, PositionStatus
from armctl.sim.bridge import serve_pty, serve_tcp
from armctl.sim.model import SimOptions

KEYS = ["x", "y", "z", "joints", "worktable", "paused", "pwm", "w0", "w1", "file_length", "file_status", "run_position"]
FAST_SIM = "sim://?clock=virtual"  # model time moves only while status waits: no machine is too slow
WATCH_SIM = "sim://?speed=20"  # --watch needs a clock that moves by itself
DEFAULT_BANNER = "armctl: no port configured (--port, ARMCTL_PORT or armctl.toml): using the built-in simulator (sim://)"


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory would change the port"


def status(*args, env=None):
    return CliRunner().invoke(main, ["status", *map(str, args)], env=env)


def the_object(result) -> dict:
    lines = result.stdout.splitlines()
    assert len(lines) == 1, result.stdout
    return json.loads(lines[0])


# --- --once --json ------------------------------------------------------------------------------


def test_once_json_prints_one_object_with_exactly_the_documented_keys():
    result = status("--once", "--json", "--port", FAST_SIM)
    assert result.exit_code == 0, result.output
    state = the_object(result)
    assert list(state) == KEYS
    assert len(state["joints"]) == 6 and len(state["worktable"]) == 3
    assert all(isinstance(v, float) for v in [state["x"], state["y"], state["z"], *state["joints"], *state["worktable"]])
    assert state["paused"] is False
    assert isinstance(state["pwm"], int) and isinstance(state["file_status"], int)
    # the simulated arm starts at the profile's fixed pose 0 with its initial PWM
    assert state["joints"] == [0.0, 0.0, 0.0, 0.0, 90.0, 0.0]
    assert state["pwm"] == 1500


def test_without_json_once_prints_one_plain_line():
    result = status("--once", "--port", FAST_SIM)
    assert result.exit_code == 0
    assert result.stdout.startswith("xyz=210.0,0.0,300.0 joints=0.00 0.00 0.00 0.00 90.00 0.00 pwm=1500 running")
    assert len(result.stdout.splitlines()) == 1


def test_with_no_port_configured_the_first_line_says_it_is_the_simulator():
    result = status("--once", "--json")
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == DEFAULT_BANNER
    assert list(the_object(result)) == KEYS


def test_an_explicit_sim_port_still_says_it_is_the_simulator():
    result = status("--once", "--json", "--port", FAST_SIM)
    assert result.stderr.splitlines()[0] == f"armctl: using the built-in simulator ({FAST_SIM})"


# --- which port: --port > ARMCTL_PORT > armctl.toml > the simulator ------------------------------


def write_toml(tmp_path, text: str) -> None:
    (tmp_path / "armctl.toml").write_text(text)


def test_port_option_beats_the_environment(tmp_path):
    write_toml(tmp_path, 'port = "loop://"\n')
    result = status("--once", "--json", "--port", "sim://?clock=virtual&seed=25", env={"ARMCTL_PORT": "loop://"})
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == "armctl: using the built-in simulator (sim://?clock=virtual&seed=25)"


def test_environment_beats_armctl_toml(tmp_path):
    write_toml(tmp_path, 'port = "loop://"\n')
    result = status("--once", "--json", env={"ARMCTL_PORT": "sim://?clock=virtual&seed=21"})
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == "armctl: using the built-in simulator (sim://?clock=virtual&seed=21)"


def test_armctl_toml_port_is_used_when_nothing_else_names_one(tmp_path):
    write_toml(tmp_path, 'port = "sim://?clock=virtual&seed=22"\n')
    result = status("--once", "--json")
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == "armctl: using the built-in simulator (sim://?clock=virtual&seed=22)"


def test_armctl_toml_in_a_parent_directory_names_a_real_port(tmp_path, monkeypatch):
    write_toml(tmp_path, 'port = "loop://"\nbaud = 4800\n')
    (tmp_path / "jobs").mkdir()
    monkeypatch.chdir(tmp_path / "jobs")
    result = status("--once", "--json", "--timeout", "0.1")
    assert result.exit_code == 1
    assert "simulator" not in result.stderr
    assert "loop:// at 4800 baud" in result.stderr  # armctl.toml's baud too


# --- ports that say nothing useful -------------------------------------------------------------


@pytest.mark.realtime
def test_a_silent_port_fails_within_the_timeout_naming_port_baud_and_nothing_received():
    started = time.monotonic()
    result = status("--once", "--json", "--port", "loop://", "--timeout", "0.3")
    elapsed = time.monotonic() - started
    assert result.exit_code == 1
    assert result.stdout == ""
    message = result.stderr.strip()
    assert message.startswith("armctl: no complete status from loop:// at 9600 baud within 0.3 s: received nothing")
    assert 0.3 <= elapsed < 0.3 + 0.7
    assert "Traceback" not in result.output


def test_the_baud_option_is_named_in_the_message():
    result = status("--once", "--port", "loop://", "--timeout", "0.1", "--baud", "115200")
    assert result.exit_code == 1
    assert "loop:// at 115200 baud within 0.1 s: received nothing" in result.stderr


@contextlib.contextmanager
def tcp_peer(chunk: bytes, period_s: float = 0.01):
    """A TCP peer on loopback that sends ``chunk`` every ``period_s`` to its one client."""
    server = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve():
        server.settimeout(5.0)
        try:
            client, _ = server.accept()
        except OSError:
            return
        with client:
            while not stop.is_set():
                try:
                    client.sendall(chunk)
                except OSError:
                    return
                stop.wait(period_s)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"socket://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        server.close()
        thread.join(2.0)


def test_a_port_that_sends_junk_says_the_bytes_never_formed_a_frame():
    with tcp_peer(bytes(range(0x20, 0x60))) as url:  # no 0xCE anywhere
        result = status("--once", "--json", "--port", url, "--timeout", "0.3")
    assert result.exit_code == 1
    message = result.stderr.strip()
    assert message.startswith(f"armctl: no complete status from {url} at 9600 baud within 0.3 s: received ")
    assert "bytes that never formed a status frame" in message
    assert "Traceback" not in result.output


def test_a_port_that_sends_only_some_kinds_names_the_ones_never_seen():
    position = bytes([0xCE]) + struct.pack(">3h", 2100, 0, 3000) + bytes([0, 0xCF])
    with tcp_peer(position) as url:
        result = status("--once", "--json", "--port", url, "--timeout", "0.3")
    assert result.exit_code == 1
    assert "status frames read, never saw: joints 1-3, joints 4-6, worktable origin" in result.stderr


def test_a_device_that_does_not_exist_is_named():
    result = status("--once", "--port", "/dev/armctl-no-such-device")
    assert result.exit_code == 1
    assert result.stderr.strip() == (
        "armctl: no such device: /dev/armctl-no-such-device (is the arm plugged in? `armctl ports` lists the ports found)"
    )


def test_once_and_watch_together_are_a_usage_error():
    result = status("--once", "--watch", "--port", FAST_SIM)
    assert result.exit_code == 2
    assert "choose --once or --watch" in result.stderr


# --- through the simulator's bridges: a real pseudo-terminal and TCP ---------------------------


@contextlib.contextmanager
def bridge_thread(serve, *args, **kwargs):
    """Run ``serve_pty``/``serve_tcp`` in a thread; yield where it listens; stop it after."""
    ready: queue.Queue = queue.Queue()
    stop = threading.Event()
    ended: list = []
    thread = threading.Thread(
        target=lambda: ended.append(serve(*args, SimOptions(), ready.put, stop=stop, time_scale=20, **kwargs)),
        daemon=True,
    )
    thread.start()
    try:
        yield ready.get(timeout=5.0)
    finally:
        stop.set()
        thread.join(2.0)
        assert not thread.is_alive()


@pytest.mark.realtime
def test_status_through_a_real_pseudo_terminal():
    with bridge_thread(serve_pty) as path:
        assert path.startswith("/dev/pts/")
        result = status("--once", "--json", "--port", path)
    assert result.exit_code == 0, result.output
    assert result.stderr == ""  # a real device: no simulator banner
    state = the_object(result)
    assert list(state) == KEYS and state["joints"] == [0.0, 0.0, 0.0, 0.0, 90.0, 0.0]


@pytest.mark.realtime
def test_status_through_socket_url_to_the_tcp_bridge():
    with bridge_thread(serve_tcp, 0) as url:
        assert url.startswith("socket://127.0.0.1:")
        result = status("--once", "--json", "--port", url)
    assert result.exit_code == 0, result.output
    assert list(the_object(result)) == KEYS


# --- --watch --------------------------------------------------------------------------------------


class FakeLink:
    """What watch_status reads from a Link: url, port.baudrate, error, clock, snapshot()."""

    def __init__(self, states, fail_after=None):
        self.url = "fake://arm"
        self.clock = time.monotonic
        self.port = types.SimpleNamespace(baudrate=9600)
        self.error = None
        self.states = list(states)
        self.calls = 0
        self.fail_after = fail_after

    on_status = None  # set by the watch: it shows only what two consecutive reports of a kind agree on

    def snapshot(self):
        state = self.states[min(self.calls, len(self.states) - 1)]
        self.calls += 1
        for frame in 2 * getattr(state, "frames_read", []) if self.on_status else []:  # each report read twice
            self.on_status(frame, 0.0)
        if self.fail_after is not None and self.calls >= self.fail_after:
            self.error = PortError("the port fake://arm went away: unplugged")
        return state, 100 * self.calls, 0, 9 * self.calls


class VirtualTime:
    """Stands in for the ``time`` module of status_watch: sleep advances a virtual clock, and
    the ``stop_after``-th sleep is the user's Ctrl-C."""

    def __init__(self, stop_after: int):
        self.now = 1000.0
        self.sleeps: list[float] = []
        self.stop_after = stop_after

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps.append(seconds)
        self.now += seconds
        if len(self.sleeps) >= self.stop_after:
            raise KeyboardInterrupt


def a_state(x: float, paused: int = 0) -> ArmState:
    state = ArmState()
    state.frames_read = [PositionStatus(x, 0, 300), JointsLowStatus(1, 2, 3), PauseStatus(paused, 1500), FileLengthStatus(10)]
    for frame in state.frames_read:
        state.update(frame, 0.0)
    return state


def test_json_watch_prints_one_json_line_per_period_until_ctrl_c(monkeypatch, capsys):
    from armctl.ui import status_watch

    clock = VirtualTime(stop_after=3)
    monkeypatch.setattr(status_watch, "time", clock)
    states = [a_state(200.0), a_state(201.5), a_state(203.0, paused=1)]
    with pytest.raises(KeyboardInterrupt):  # Ctrl-C leaves to the CLI, which exits 130
        status_watch.watch_status(FakeLink(states), 9600, as_json=True)
    lines = capsys.readouterr().out.splitlines()
    records = [json.loads(line) for line in lines]
    assert [{k: v for k, v in r.items() if k != "t"} for r in records] == [s.to_json() for s in states]
    assert all(isinstance(r["t"], (int, float)) for r in records)  # every record carries its time (issue 26)
    assert clock.sleeps == [status_watch.JSON_LINE_S] * 3
    assert status_watch.JSON_LINE_S <= 0.27  # at least one line per rotation of the nine kinds


def test_plain_watch_off_a_terminal_prints_plain_lines_never_cursor_codes(monkeypatch, capsys):
    from armctl.ui import status_watch

    clock = VirtualTime(stop_after=2)
    monkeypatch.setattr(status_watch, "time", clock)
    with pytest.raises(KeyboardInterrupt):
        status_watch.watch_status(FakeLink([a_state(200.0), a_state(210.0)]), 9600, as_json=False)  # stdout: not a tty
    text = capsys.readouterr().out
    lines = text.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("xyz=200.0,0.0,300.0 joints=1.00 2.00 3.00 — — — pwm=1500 running")
    assert lines[1].startswith("xyz=210.0,0.0,300.0 joints=1.00 2.00 3.00 — — — pwm=1500 running")
    assert "\x1b" not in text
    assert clock.sleeps == [status_watch.PLAIN_LINE_S] * 2


def test_a_port_lost_while_watching_is_an_error_not_a_clean_exit(monkeypatch):
    from armctl.ui import status_watch

    monkeypatch.setattr(status_watch, "time", VirtualTime(stop_after=99))
    with pytest.raises(PortError, match="went away"):
        status_watch.watch_status(FakeLink([a_state(200.0)], fail_after=2), 9600, as_json=True)


@pytest.mark.realtime
def test_json_watch_end_to_end_then_ctrl_c_exits_130(tmp_path):
    process = subprocess.Popen(
        [sys.executable, "-m", "armctl", "status", "--json", "--watch", "--port", WATCH_SIM],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
        env={k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"},
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        lines = [process.stdout.readline() for _ in range(3)]
        process.send_signal(signal.SIGINT)
        rest, err = process.communicate(timeout=10)
    finally:
        process.kill()
    assert process.returncode == 130, err  # README: 130 Ctrl-C
    assert err.splitlines()[-1] == "armctl: interrupted"
    objects = [json.loads(line) for line in lines + rest.splitlines()]
    assert all(list(o) == ["t"] + KEYS for o in objects)  # every --watch record carries its time first (issue 26)
    assert objects[-1]["joints"] == [0.0, 0.0, 0.0, 0.0, 90.0, 0.0]
    assert "Traceback" not in err


# --- ports ----------------------------------------------------------------------------------------


def test_ports_lists_each_port_found_with_description_and_hardware_id(monkeypatch):
    from serial.tools import list_ports

    found = [types.SimpleNamespace(device="/dev/ttyUSB0", description="CH340 serial", hwid="USB VID:PID=1A86:7523"),
             types.SimpleNamespace(device="/dev/ttyACM0", description="arm", hwid="USB VID:PID=2341:0043")]
    monkeypatch.setattr(list_ports, "comports", lambda: found)
    result = CliRunner().invoke(main, ["ports"])
    assert result.exit_code == 0
    assert result.stdout.splitlines() == [
        "/dev/ttyACM0\tarm\tUSB VID:PID=2341:0043",
        "/dev/ttyUSB0\tCH340 serial\tUSB VID:PID=1A86:7523",
    ]


def test_ports_says_when_none_were_found(monkeypatch):
    from serial.tools import list_ports

    monkeypatch.setattr(list_ports, "comports", lambda: [])
    result = CliRunner().invoke(main, ["ports"])
    assert result.exit_code == 0
    assert result.stdout.startswith("no serial ports found")


def test_ports_on_this_machine_lists_something_or_says_none_were_found():
    result = CliRunner().invoke(main, ["ports"])
    assert result.exit_code == 0
    lines = result.stdout.splitlines()
    assert lines and (lines[0].startswith("no serial ports found") or all(line.count("\t") == 2 for line in lines))
