"""The port edge (armctl/host/link.py): which port, what an open failure says, and a Link whose port
fails.

``resolve_port`` and ``describe_open_error`` are pure and tested on values; ``Link`` runs its
real reader thread over fake ports (short real-time waits only: the reader thread is the code
under test) and over a real pseudo-terminal whose other end goes away.
"""

from __future__ import annotations

import errno
import os
import socket
import threading
import time

import pytest
import serial

from armctl.core.armstate import ArmState
from armctl.errors import ConfigError, PortError
from armctl.host.link import SIMULATOR_URL, Link, PortChoice, describe_open_error, open_port, resolve_port
from armctl.core.protocol import PositionStatus

# --- resolve_port: --port > ARMCTL_PORT > armctl.toml > the simulator ----------------------------


@pytest.mark.parametrize(
    "option, environ, config, url, origin",
    [
        ("/dev/ttyUSB0", {"ARMCTL_PORT": "socket://h:1"}, {"port": "/dev/ttyACM0"}, "/dev/ttyUSB0", "--port"),
        (None, {"ARMCTL_PORT": "socket://h:1"}, {"port": "/dev/ttyACM0"}, "socket://h:1", "ARMCTL_PORT"),
        (None, {}, {"port": "/dev/ttyACM0"}, "/dev/ttyACM0", "armctl.toml"),
        (None, {}, {"baud": 9600}, SIMULATOR_URL, "default"),
        (None, {}, None, SIMULATOR_URL, "default"),
    ],
    ids=["option", "environment", "toml", "toml-without-port", "nothing"],
)
def test_resolve_port_precedence(option, environ, config, url, origin):
    assert resolve_port(option, environ=environ, config=config) == PortChoice(url, origin)


@pytest.mark.parametrize(
    "option, environ, config, message",
    [
        ("", {"ARMCTL_PORT": "sim://?speed=2"}, {}, r"^--port is empty"),
        (" ", {}, {}, r"^--port is empty"),
        (None, {"ARMCTL_PORT": ""}, {"port": "/dev/ttyACM0"}, r"^ARMCTL_PORT is set but empty"),
        (None, {}, {"port": ""}, r"^armctl\.toml: port = '' must be a device path or URL"),
        (None, {}, {"port": []}, r"^armctl\.toml: port = \[\] must be a device path or URL"),
        (None, {}, {"port": 5}, r"^armctl\.toml: port = 5 must be a device path or URL"),
    ],
    ids=["empty-option", "blank-option", "empty-environment", "empty-toml", "list-toml", "number-toml"],
)
def test_a_port_given_empty_or_of_the_wrong_type_is_a_config_error_not_the_simulator(option, environ, config, message):

    with pytest.raises(ConfigError, match=message):
        resolve_port(option, environ=environ, config=config)


def test_the_default_says_it_is_the_simulator_and_a_real_port_says_nothing():
    default = resolve_port(None, environ={}, config={})
    assert default.is_simulator
    assert default.banner() == (
        "armctl: no port configured (--port, ARMCTL_PORT or armctl.toml): using the built-in simulator (sim://)"
    )
    chosen = resolve_port("sim://?speed=4", environ={}, config={})
    assert chosen.is_simulator and chosen.banner() == "armctl: using the built-in simulator (sim://?speed=4)"
    real = resolve_port("/dev/ttyUSB0", environ={}, config={})
    assert not real.is_simulator and real.banner() is None


def test_resolve_port_reads_the_process_environment_by_default(monkeypatch):
    monkeypatch.setenv("ARMCTL_PORT", "socket://127.0.0.1:7000")
    assert resolve_port(None, config={"port": "/dev/ttyACM0"}) == PortChoice("socket://127.0.0.1:7000", "ARMCTL_PORT")


# --- what an open failure says ------------------------------------------------------------------


def test_no_such_device():
    error = serial.SerialException(errno.ENOENT, "could not open port /dev/ttyUSB0: [Errno 2] No such file or directory")
    assert describe_open_error("/dev/ttyUSB0", error) == (
        "no such device: /dev/ttyUSB0 (is the arm plugged in? `armctl ports` lists the ports found)"
    )


def test_permission_denied_gives_the_dialout_hint():
    error = serial.SerialException(errno.EACCES, "could not open port /dev/ttyUSB0: [Errno 13] Permission denied")
    message = describe_open_error("/dev/ttyUSB0", error)
    assert message.startswith("permission denied opening /dev/ttyUSB0")
    assert "sudo usermod -aG dialout $USER" in message


@pytest.mark.parametrize(
    "error",
    [
        serial.SerialException(errno.EBUSY, "could not open port /dev/ttyUSB0: [Errno 16] Device or resource busy"),
        serial.SerialException(errno.EAGAIN, "Could not exclusively lock port /dev/ttyUSB0: [Errno 11] Resource "
                                             "temporarily unavailable"),
    ],
    ids=["EBUSY", "lock"],
)
def test_busy(error):
    assert describe_open_error("/dev/ttyUSB0", error) == (
        "/dev/ttyUSB0 is busy: another program (another armctl, a serial monitor) has it open"
    )


def test_refused_as_an_os_error():
    message = describe_open_error("socket://127.0.0.1:7000", ConnectionRefusedError(errno.ECONNREFUSED, "Connection refused"))
    assert message == "connection refused by socket://127.0.0.1:7000: is the bridge (e.g. `armctl sim --tcp`) running?"


def closed_tcp_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_refused_by_pyserial_socket_url():
    url = f"socket://127.0.0.1:{closed_tcp_port()}"
    with pytest.raises(PortError) as caught:
        open_port(url)
    assert str(caught.value) == f"connection refused by {url}: is the bridge (e.g. `armctl sim --tcp`) running?"


def test_anything_else_keeps_pyserials_words():
    assert describe_open_error("bogus://x", ValueError("invalid URL, protocol 'bogus' not known")) == (
        "cannot open bogus://x: invalid URL, protocol 'bogus' not known"
    )


def test_open_port_turns_real_failures_into_port_errors():
    with pytest.raises(PortError, match=r"^no such device: /dev/armctl-no-such-device "):
        open_port("/dev/armctl-no-such-device")
    with pytest.raises(PortError, match=r"^cannot open bogus://x: "):
        open_port("bogus://x")
    with pytest.raises(ConfigError, match=r"^speed must be a number 0.01…1000, not '-1' in 'sim://\?speed=-1'"):
        open_port("sim://?speed=-1")


def test_a_device_opened_twice_is_busy():
    master, slave = os.openpty()
    path = os.ttyname(slave)
    try:
        first = open_port(path)
        try:
            with pytest.raises(PortError) as caught:
                open_port(path)
            assert str(caught.value) == f"{path} is busy: another program (another armctl, a serial monitor) has it open"
        finally:
            first.close()
    finally:
        os.close(master)
        os.close(slave)


# --- Link over ports that fail ------------------------------------------------------------------


class QuietPort:
    """Reads time out with nothing (like a silent line) until ``fail`` is set, then raise."""

    url = "fake://"

    def __init__(self, chunks=()):
        self.chunks = list(chunks)
        self.fail = threading.Event()
        self.closed = False
        self.written: list[bytes] = []

    def read(self, size):
        if self.fail.is_set():
            raise serial.SerialException("read failed: [Errno 5] Input/output error")
        if self.chunks:
            return self.chunks.pop(0)
        self.fail.wait(0.01)
        return b""

    def write(self, data):
        self.written.append(bytes(data))
        return len(data)

    def close(self):
        self.closed = True


def test_a_port_that_raises_on_read_sets_error_and_write_raises_it():
    port = QuietPort()
    with Link(port, "fake://arm") as link:
        link.start()
        link.write(b"\x01")
        port.fail.set()
        with pytest.raises(PortError, match=r"^the port fake://arm went away: read failed"):
            link.wait_until(lambda state: False, timeout_s=5.0)
        assert isinstance(link.error, PortError)
        with pytest.raises(PortError) as caught:
            link.write(b"\x02")
        assert caught.value is link.error
    assert port.written == [b"\x01"]
    assert port.closed


def test_a_port_that_raises_on_write_is_a_port_error():
    class Unplugged(QuietPort):
        def write(self, data):
            raise serial.SerialTimeoutException("Write timeout")

    with Link(Unplugged(), "fake://arm") as link:
        with pytest.raises(PortError, match=r"^writing to fake://arm failed: Write timeout"):
            link.write(b"\x01")


@pytest.mark.realtime
def test_wait_until_returns_false_on_timeout():
    with Link(QuietPort(), "fake://arm") as link:
        link.start()
        started = time.monotonic()
        assert link.wait_until(lambda state: state.complete, timeout_s=0.1) is False
        assert 0.1 <= time.monotonic() - started < 0.6
        assert link.error is None


def test_wait_until_reads_the_clock_it_is_given():
    ticks = iter(range(0, 1000, 10))  # every reading is 10 s later: the deadline passes at once
    with Link(QuietPort(), "fake://arm", clock=lambda: float(next(ticks))) as link:
        started = time.monotonic()
        assert link.wait_until(lambda state: False, timeout_s=5.0) is False
        assert time.monotonic() - started < 0.5


def test_status_bytes_in_any_chunks_reach_the_state_and_the_callback():
    position = PositionStatus(210.0, -12.5, 300.0).encode()
    stream = b"\x00junk" + position
    seen = []
    port = QuietPort([stream[:3], stream[3:8], stream[8:]])
    with Link(port, "fake://arm", state=ArmState(), on_status=lambda frame, now: seen.append(frame)) as link:
        link.start()
        assert link.wait_until(lambda state: state.x_mm is not None, timeout_s=2.0)
        state, received, skipped, count = link.snapshot()
    assert state.position_mm == (210.0, -12.5, 300.0)
    assert (received, skipped, count) == (len(stream), 5, 1)
    assert seen == [PositionStatus(210.0, -12.5, 300.0)]


def test_a_pseudo_terminal_whose_other_end_goes_away_is_a_port_error():
    master, slave = os.openpty()
    path = os.ttyname(slave)
    os.close(slave)
    link = Link.open(path)
    try:
        os.write(master, PositionStatus(1.0, 2.0, 3.0).encode())
        assert link.wait_until(lambda state: state.x_mm == 1.0, timeout_s=2.0)
        os.close(master)
        master = None
        with pytest.raises(PortError, match=rf"^the port {path} went away"):
            link.wait_until(lambda state: False, timeout_s=2.0)
    finally:
        link.close()
        if master is not None:
            os.close(master)


@pytest.mark.timeout(20)
def test_a_read_that_finds_the_pseudo_terminals_data_gone_is_not_a_port_that_went_away(monkeypatch):
    """pyserial raises "device reports readiness to read but returned no data" when select()
    said readable and read() got nothing: on a tty that is still there it is another holder
    (a second reader, a flush: here a TCIFLUSH between the two) taking the bytes; a hung-up tty
    says POLLHUP too.  The link keeps reading: the next frame reaches its state, no error."""
    termios = pytest.importorskip("termios")
    import select as real_select

    import serial.serialposix as serialposix

    master, slave = os.openpty()
    path = os.ttyname(slave)
    os.close(slave)
    flushed = threading.Event()

    class FlushAfterSelect:  # the bytes gone between pyserial's select() and its read(), once
        error = real_select.error

        @staticmethod
        def select(readers, writers, errors, timeout=None):
            ready = real_select.select(readers, writers, errors, timeout)
            port_fd = readers[0]  # (a read's select: [the port, pyserial's abort pipe])
            if not writers and not flushed.is_set() and port_fd in ready[0]:
                termios.tcflush(port_fd, termios.TCIFLUSH)
                flushed.set()
            return ready

    monkeypatch.setattr(serialposix, "select", FlushAfterSelect)
    link = Link.open(path)
    try:
        os.write(master, PositionStatus(1.0, 2.0, 3.0).encode())
        assert flushed.wait(5.0)
        os.write(master, PositionStatus(4.0, 5.0, 6.0).encode())
        assert link.wait_until(lambda state: state.x_mm == 4.0, timeout_s=2.0), link.error
        assert link.error is None
    finally:
        link.close()
        os.close(master)


def test_a_tty_that_stays_readable_with_nothing_to_read_is_a_port_that_went_away():
    """The same error again and again on a tty that polls no hang-up (a driver that never says
    POLLHUP) is not another holder taking bytes: after ``TAKEN_READS_MAX`` reads in a row, gone."""
    from armctl.host.link import TAKEN_READS_MAX

    master, slave = os.openpty()
    reads = []

    class EmptyTty(QuietPort):
        fd = slave

        def read(self, size=1):
            reads.append(size)
            raise serial.SerialException("device reports readiness to read but returned no data "
                                         "(device disconnected or multiple access on port?)")

    try:
        with Link(EmptyTty(), "/dev/ttyFAKE") as link:
            link.start()
            with pytest.raises(PortError, match=r"^the port /dev/ttyFAKE went away: device reports readiness"):
                link.wait_until(lambda state: False, timeout_s=5.0)
        assert len(reads) == TAKEN_READS_MAX + 1
    finally:
        os.close(master)
        os.close(slave)


@pytest.mark.realtime
@pytest.mark.timeout(30)
def test_armctl_status_watch_goes_on_while_another_program_reads_the_same_tty(sim_pty):
    """``armctl status --watch`` (the installed command, a fresh process) on ``armctl sim --pty``
    while another program that takes no lock (a serial monitor, a modem manager probing the
    device) reads the same tty for a second: the bytes it takes are lost to armctl, the port did
    not go away (before: "went away: device reports readiness to read but returned no data" in 10
    of 10 such runs)."""
    import signal
    import subprocess
    import sys
    from pathlib import Path

    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    watch = subprocess.Popen([str(Path(sys.executable).with_name("armctl")), "status", "--watch", "--json", "--port", sim_pty],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    try:
        time.sleep(1.0)  # it has the port open and reads
        other = os.open(sim_pty, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            end = time.monotonic() + 1.0
            while time.monotonic() < end and watch.poll() is None:
                try:
                    os.read(other, 64)
                except BlockingIOError:
                    pass
        finally:
            os.close(other)
        assert watch.poll() is None, watch.communicate()[1]
        watch.send_signal(signal.SIGINT)
        stderr = watch.communicate(timeout=10)[1]
    finally:
        watch.kill()
    assert "went away" not in stderr, stderr
