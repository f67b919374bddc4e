"""The simulated arm behind a pseudo-terminal or a TCP socket, in real time.

Strategy: one loop per transport, both thin: wait (``poll``/``select``) until host bytes come
in or the next status byte is due, hand what came in to the ``RealtimeArm``, send what it
produced.  The loop ends, closing everything it opened, when

- the peer goes away — the pty's slave is closed again after a program had it open (POLLHUP),
  or the TCP client disconnects; unless ``keep_serving``, which waits for the next program
  instead (the same arm, running meanwhile, its output discarded);
- ``stop`` (a ``threading.Event``) is set — tests and embedding callers use it;
- the user presses Ctrl-C (KeyboardInterrupt is caught here, not re-raised).

Each function returns why it ended: ``"peer closed"``, ``"stopped"`` or ``"interrupted"``.
With ``write_buffer_bytes`` the loop reads host bytes only while the arm's write buffer has room
(the rest wait in the pty's or socket's own buffer); with ``read_granularity_ms`` it sends status
bytes at the ticks ``RealtimeArm.poll`` releases them.
Until a program opens the pty, the arm runs and its status bytes are discarded (a tty would
otherwise hand the first reader a backlog of stale frames).
On Linux the pty's line rate is the one the program sets on it, as a serial port's (``PtyLine``;
the pty starts at the arm's): at another rate the arm hears nothing it can frame and the program reads
noise, as through a ``sim://`` port set wrong (``protocol_sim.LineNoise``).
"""

from __future__ import annotations

import errno
import os
import select
import socket
import sys
import threading
from typing import Callable

from ..host.posix_terminal import require_posix_terminal
from ..core.protocol import FRAME_SIZE
from .model import SimOptions, SimulatedArm
from .realtime import RealtimeArm

PEER_CLOSED, STOPPED, INTERRUPTED = "peer closed", "stopped", "interrupted"
IDLE_WAIT_S = 0.05  # longest wait between checks of ``stop`` and the peer
NO_PEER_WAIT_S = 0.01  # how often to look for a program opening the pty, or the next TCP client (keeps the first
# status bytes it gets fresh: output made while nobody listened is discarded)
READ_CHUNK = 4096
ROOM_WAIT_S = 0.001  # the shortest wait for room in the write buffer (a byte at 9600 baud)
TCP_HOST = "127.0.0.1"


def _wait_s(arm: RealtimeArm) -> float:
    due = arm.wall_seconds_until_output()
    wait_s = IDLE_WAIT_S if due is None else min(IDLE_WAIT_S, due)
    if arm.write_room() == 0:  # the host's bytes wait in the pty until the buffer has room
        wait_s = min(wait_s, max(arm.model_seconds_until_room(FRAME_SIZE) / arm.time_scale, ROOM_WAIT_S))
    return wait_s


def _take_room(arm: RealtimeArm) -> int:
    """How many host bytes to read now: all there are, or what the write buffer has room for
    (``write_buffer_bytes``: the rest stay in the pty's or socket's own buffer, so the host's
    write blocks when that fills, as on a real line)."""
    room = arm.write_room()
    return READ_CHUNK if room is None else min(room, READ_CHUNK)


# the rates termios names (a program may also set one it cannot name: pyserial's custom rates)
_STANDARD_RATES = (50, 75, 110, 134, 150, 200, 300, 600, 1200, 1800, 2400, 4800, 9600, 19200, 38400, 57600, 115200,
                   230400, 460800, 500000, 576000, 921600, 1000000, 1152000, 1500000, 2000000, 2500000, 3000000,
                   3500000, 4000000)


class PtyLine:
    """The line between the program on the pty and the arm, at the rate the program set (a pty's
    master reads its slave's termios): at the arm's rate clean; at another rate termios names, a
    line set wrong — the arm hears nothing (``to_arm``), the program reads noise (``to_host``); at
    a rate termios cannot name, taken as right."""

    def __init__(self, master_fd: int, arm_baud: int, seed: int) -> None:
        import termios

        self._fd, self._arm_baud, self._seed, self._tcgetattr = master_fd, arm_baud, seed, termios.tcgetattr
        self._rates = {getattr(termios, f"B{rate}"): rate for rate in _STANDARD_RATES if hasattr(termios, f"B{rate}")}
        self._noise, self._noise_rate = None, None

    def speed_code(self) -> int | None:
        """The termios code of the arm's rate (the pty starts at it), None if it has none."""
        return next((code for code, rate in self._rates.items() if rate == self._arm_baud), None)

    def check(self) -> None:
        """Read the rate the program set now."""
        rate = self._rates.get(self._tcgetattr(self._fd)[5])
        if rate is None or rate == self._arm_baud:
            self._noise = self._noise_rate = None
        elif rate != self._noise_rate:
            from .protocol_sim import LineNoise

            self._noise, self._noise_rate = LineNoise(rate, self._arm_baud, self._seed), rate

    def to_arm(self, data: bytes) -> bytes:
        return data if self._noise is None else b""

    def to_host(self, data: bytes) -> bytes:
        return data if self._noise is None else self._noise.heard(data)


def _stopped(stop: threading.Event | None) -> bool:
    return stop is not None and stop.is_set()


def serve_pty(
    options: SimOptions,
    on_ready: Callable[[str], None],
    stop: threading.Event | None = None,
    time_scale: float | None = None,  # None: the options' (speed=)
    model: SimulatedArm | None = None,
    keep_serving: bool = False,
    on_arm: Callable[[RealtimeArm], None] | None = None,
) -> str:
    """Run the arm on a new pseudo-terminal; ``on_ready(path)`` gets its slave path.

    ``model``: an arm built by the caller (to inspect it afterwards), else one from ``options``.
    ``keep_serving``: when a program closes the pty, wait for the next one instead of ending
    (``armctl sim --pty``: `armctl status`, then `armctl run`, against the same arm).
    ``on_arm``: told the ``RealtimeArm`` before ``on_ready`` (its clock start, for ``--stats``).
    ``NeedsPosixTerminal`` where there is no termios (Windows): nothing is opened."""
    require_posix_terminal("armctl sim --pty", "serve the arm with `armctl sim --tcp PORT` instead")
    import termios  # here, not at the top: serve_tcp needs neither and works on Windows
    import tty

    model = model or SimulatedArm(options)
    master_fd, slave_fd = os.openpty()
    # (Linux: a pty's master reads its slave's termios, checked there; elsewhere the rate is not read)
    line = PtyLine(master_fd, model.options.baud, model.options.seed) if sys.platform.startswith("linux") else None
    try:
        tty.setraw(slave_fd, termios.TCSANOW)
        code = None if line is None else line.speed_code()
        if code is not None:  # the pty starts at the arm's rate, a serial port left at the right one
            attributes = termios.tcgetattr(slave_fd)
            attributes[4] = attributes[5] = code
            termios.tcsetattr(slave_fd, termios.TCSANOW, attributes)
        path = os.ttyname(slave_fd)
    except BaseException:
        os.close(master_fd)
        os.close(slave_fd)
        raise
    os.close(slave_fd)  # so that POLLHUP tells whether a program has the slave open
    arm = RealtimeArm(model, options.time_scale if time_scale is None else time_scale)
    if on_arm is not None:
        on_arm(arm)  # (its clock: ``armctl sim --stats`` places the model's times on the machine's clock)
    try:
        on_ready(path)
        return _pump_pty(master_fd, arm, stop, keep_serving, line)
    except KeyboardInterrupt:
        return INTERRUPTED
    finally:
        os.close(master_fd)


def _pump_pty(master_fd: int, arm: RealtimeArm, stop: threading.Event | None, keep_serving: bool = False,
              line: PtyLine | None = None) -> str:
    poller = select.poll()
    poller.register(master_fd, select.POLLIN)
    peer_seen = False
    while not _stopped(stop):
        room = _take_room(arm)
        poller.modify(master_fd, select.POLLIN if room else 0)  # (POLLHUP is reported either way)
        events = dict(poller.poll(_wait_s(arm) * 1000.0))
        hung_up = bool(events.get(master_fd, 0) & (select.POLLHUP | select.POLLERR))
        if hung_up:
            if peer_seen and not keep_serving:
                return PEER_CLOSED
            peer_seen = False  # wait for the next program to open the pty; the arm keeps its state
            arm.poll()  # nobody listens yet: the arm runs, its output is discarded
            if stop is not None:
                stop.wait(NO_PEER_WAIT_S)
            else:
                select.select([], [], [], NO_PEER_WAIT_S)
            continue
        peer_seen = True
        try:
            if line is not None:
                line.check()
            if room and events.get(master_fd, 0) & select.POLLIN:
                data = os.read(master_fd, room)
                arm.write(data if line is None else line.to_arm(data))
            output = arm.poll()
            if output and line is not None:
                output = line.to_host(output)
            if output:
                os.write(master_fd, output)
        except OSError as error:
            if error.errno in (errno.EIO, errno.EBADF):
                return PEER_CLOSED
            raise
    return STOPPED


def serve_tcp(
    port: int,
    options: SimOptions,
    on_ready: Callable[[str], None],
    stop: threading.Event | None = None,
    time_scale: float | None = None,  # None: the options' (speed=)
    model: SimulatedArm | None = None,
    keep_serving: bool = False,
) -> str:
    """Serve one client on 127.0.0.1:``port`` (0 = any free port); ``on_ready`` gets the
    pyserial URL to open, ``socket://127.0.0.1:PORT``.  The arm's clock starts when the first
    client connects.  ``model`` as for ``serve_pty``.  ``keep_serving``: when the client
    disconnects, serve the next one, one at a time, the same arm (``armctl sim --tcp``)."""
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind((TCP_HOST, port))
        server.listen(1)
        on_ready(f"socket://{TCP_HOST}:{server.getsockname()[1]}")
        arm = None
        while True:
            client = _accept(server, stop, arm)
            if client is None:
                return STOPPED
            with client:
                client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                if arm is None:
                    arm = RealtimeArm(model or SimulatedArm(options), options.time_scale if time_scale is None else time_scale)
                ended = _pump_tcp(client, arm, stop)
            if ended != PEER_CLOSED or not keep_serving:
                return ended
    except KeyboardInterrupt:
        return INTERRUPTED
    finally:
        server.close()


def _accept(server: socket.socket, stop: threading.Event | None, arm: RealtimeArm | None = None) -> socket.socket | None:
    """The next client; meanwhile ``arm`` (once a client had it) runs, its output discarded."""
    while not _stopped(stop):
        readable, _, _ = select.select([server], [], [], IDLE_WAIT_S if arm is None else NO_PEER_WAIT_S)
        if readable:
            client, _address = server.accept()
            return client
        if arm is not None:
            arm.poll()
    return None


def _pump_tcp(client: socket.socket, arm: RealtimeArm, stop: threading.Event | None) -> str:
    while not _stopped(stop):
        room = _take_room(arm)
        readable, _, _ = select.select([client] if room else [], [], [], _wait_s(arm))
        try:
            if readable:
                data = client.recv(room)
                if not data:
                    return PEER_CLOSED
                arm.write(data)
            output = arm.poll()
            if output:
                client.sendall(output)
        except (ConnectionError, OSError):
            return PEER_CLOSED
    return STOPPED
