"""The simulator's real-time edges: the ``sim://`` pyserial URL and the pty / TCP bridges.

These are the only simulator tests that run on the wall clock (marked ``realtime``); each stays
well under a second by running the arm faster than real time (``speed=``/``time_scale``).  Ctrl-C
is a real SIGINT through the ``ctrl_c`` fixture (tests/conftest.py), so it arrives even when the
runner was started with SIGINT ignored."""

from __future__ import annotations

import os
import queue
import threading
import time

import pytest
import serial

import armctl.sim  # noqa: F401 — registers sim:// with pyserial
from armctl.core.protocol import FRAME_SIZE, STATUS_SIZE, Delay, MCode, PositionStatus, StatusReader
from armctl.sim.bridge import INTERRUPTED, PEER_CLOSED, STOPPED, serve_pty, serve_tcp
from armctl.sim.model import SimOptions, SimulatedArm
from armctl.sim.protocol_sim import parse_sim_url


def test_importing_armctl_sim_registers_the_scheme():
    assert "armctl.sim" in serial.protocol_handler_packages


# --- sim:// ------------------------------------------------------------------------------------


@pytest.mark.realtime
def test_a_frame_written_to_sim_lands_and_status_comes_back():
    with serial.serial_for_url("sim://", timeout=1.0) as port:
        port.write(MCode(3).encode())
        assert 0 < port.out_waiting <= FRAME_SIZE  # 48 bytes take 50 ms on the simulated wire
        data = port.read(4 * STATUS_SIZE)
        frames = StatusReader().feed(data)
        assert len(frames) == 4 and isinstance(frames[0], PositionStatus)
        port.flush()
        assert port.out_waiting == 0
        deadline = time.monotonic() + 1.0
        while not port.model.execution_log and time.monotonic() < deadline:
            port.read(STATUS_SIZE)
        assert [f.command for f in port.model.frames_received] == [MCode(3)]
        assert port.model.execution_log[0].outcome == "done"


@pytest.mark.realtime
def test_sim_read_honours_the_timeout_without_busy_waiting():
    with serial.serial_for_url("sim://", timeout=0.05) as port:
        port.reset_input_buffer()
        started, cpu_started = time.monotonic(), time.process_time()
        data = port.read(10_000)
        elapsed, cpu = time.monotonic() - started, time.process_time() - cpu_started
        assert 0.045 <= elapsed < 0.5
        assert cpu < elapsed / 2  # it slept until each status frame was due
        assert STATUS_SIZE <= len(data) <= (elapsed / 0.030 + 2) * STATUS_SIZE  # a frame per 30 ms
        port.timeout = 0
        since = time.monotonic()
        later = len(port.read(10_000))  # only what arrived since: a frame per 30 ms (plus one in flight)
        assert later <= ((time.monotonic() - since) / 0.030 + 2) * STATUS_SIZE


@pytest.mark.realtime
def test_sim_in_waiting_and_reset_input_buffer():
    with serial.serial_for_url("sim://", timeout=0.1) as port:
        time.sleep(0.1)
        assert port.in_waiting >= 3 * STATUS_SIZE
        since = time.monotonic()
        port.reset_input_buffer()
        assert port.in_waiting <= ((time.monotonic() - since) / 0.030 + 2) * STATUS_SIZE


def test_sim_url_options_reach_the_model():
    options = parse_sim_url(
        "sim://?speed=4&slowdown=1.3&seed=7&baud=115200&control=arrival&loss=0.05&corrupt=0.01&noise=0.02&fifo=50"
    )
    assert options.time_scale == 4
    assert options == SimOptions(
        baud=115200, speed_factor=1.3, control_frames="arrival", fifo_frames=50, status_loss_rate=0.05,
        status_corrupt_rate=0.01, noise_rate=0.02, seed=7, time_scale=4,
    )
    with serial.serial_for_url("sim://?slowdown=1.3", baudrate=19200) as port:
        assert port.model.options.baud == 19200 and port.model.options.speed_factor == 1.3


def test_a_profile_path_in_the_url(tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text("[speed]\nmax_joint_deg_s = 30.0\n", encoding="utf-8")
    with serial.serial_for_url(f"sim://?profile={path}") as port:
        assert port.model.profile.speed.max_joint_deg_s == 30.0


@pytest.mark.parametrize(
    "url, message",
    [
        ("sim://?sped=4", "unknown option 'sped' \\(did you mean 'speed'\\?\\)"),
        ("sim://?speed=0", "speed must be a number 0.01…1000, not '0'"),
        ("sim://?loss=2", "loss must be a number 0…1, not '2'"),
        ("sim://?control=later", "control must be 'queued' or 'arrival'"),
        ("sim://?seed=x", "seed must be a whole number 0…"),
        ("sim://?seed=1&seed=2", "given 2 times"),
        ("sim://?profile=/no/such/profile.toml", "file not found"),
    ],
)
def test_bad_sim_urls_raise_serial_exception_with_a_clear_message(url, message):
    with pytest.raises(serial.SerialException, match=message):
        serial.serial_for_url(url)


@pytest.mark.realtime
def test_a_reader_thread_and_a_writer_thread_share_the_port():
    with serial.serial_for_url("sim://?speed=50", timeout=0.02) as port:
        received = bytearray()
        done = threading.Event()

        def read_loop():
            while not done.is_set():
                received.extend(port.read(256))

        reader = threading.Thread(target=read_loop)
        reader.start()
        for k in range(10):
            port.write(Delay(10).encode())
        port.flush()
        time.sleep(0.05)
        done.set()
        reader.join(1.0)
        assert not reader.is_alive()
        assert len(port.model.frames_received) == 10
        assert StatusReader().feed(bytes(received))


@pytest.mark.realtime
def test_close_wakes_a_blocked_reader():
    port = serial.serial_for_url("sim://", timeout=None)
    result = []
    reader = threading.Thread(target=lambda: result.append(port.read(10_000_000)))
    reader.start()
    time.sleep(0.05)
    port.close()
    reader.join(1.0)
    assert not reader.is_alive() and result


# --- bridges ------------------------------------------------------------------------------------


def _serve_in_thread(serve, *args, **kwargs):
    ready: queue.Queue = queue.Queue()
    result: list = []
    thread = threading.Thread(target=lambda: result.append(serve(*args, on_ready=ready.put, **kwargs)))
    thread.start()
    return ready.get(timeout=2.0), thread, result


@pytest.mark.realtime
@pytest.mark.parametrize("kind", ["pty", "tcp"])
def test_a_bridge_serves_the_arm_until_the_peer_goes_away(kind):
    model = SimulatedArm()
    if kind == "pty":
        address, thread, result = _serve_in_thread(serve_pty, SimOptions(), time_scale=5.0, model=model)
        assert address.startswith("/dev/") and os.path.exists(address)
        port = serial.Serial(address, timeout=1.0)
    else:
        address, thread, result = _serve_in_thread(serve_tcp, 0, SimOptions(), time_scale=5.0, model=model)
        assert address.startswith("socket://127.0.0.1:")
        port = serial.serial_for_url(address, timeout=1.0)
    with port:
        port.write(MCode(5).encode())
        frames = StatusReader().feed(port.read(6 * STATUS_SIZE))
        assert len(frames) >= 5
        deadline = time.monotonic() + 1.0
        while not model.frames_received and time.monotonic() < deadline:
            port.read(STATUS_SIZE)  # the frame lands 10 ms (wall) after it was read from the peer
    thread.join(2.0)
    assert not thread.is_alive() and result == [PEER_CLOSED]
    assert [f.command for f in model.frames_received] == [MCode(5)]


@pytest.mark.realtime
@pytest.mark.parametrize("serve, args", [(serve_pty, ()), (serve_tcp, (0,))])
def test_a_bridge_stops_when_asked(serve, args):
    stop = threading.Event()
    _address, thread, result = _serve_in_thread(serve, *args, SimOptions(), stop=stop)
    stop.set()
    thread.join(1.0)
    assert not thread.is_alive() and result == [STOPPED]


@pytest.mark.realtime
@pytest.mark.timeout(10)
def test_serve_pty_exits_cleanly_on_ctrl_c(ctrl_c):
    paths = []

    def on_ready(path):
        paths.append(path)
        ctrl_c(0.1)

    assert serve_pty(SimOptions(), on_ready) == INTERRUPTED
    assert paths and not os.path.exists(paths[0])  # the pty went away with its master


@pytest.mark.realtime
@pytest.mark.timeout(10)
def test_serve_tcp_exits_cleanly_on_ctrl_c_while_waiting_for_a_client(ctrl_c):
    assert serve_tcp(0, SimOptions(), lambda url: ctrl_c(0.1)) == INTERRUPTED
