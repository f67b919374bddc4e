"""The port edge: choose a port, open it, read status frames in a thread, write frames.

Strategy (after pyserial and python-can): every port is a pyserial URL — a device path,
``socket://``, ``rfc2217://`` or armctl's own ``sim://`` — opened with ``serial_for_url``, so
nothing above this module knows whether a real arm is attached.  A reader thread feeds bytes
to the pure ``StatusReader`` and merges frames into an ``ArmState`` under a lock; callers take
snapshots or wait on a condition.  OS failures become ``PortError`` with a sentence a user can
act on (no such device, permission denied with the dialout hint, busy, vanished).

The link owns the port's one ``Clock`` (armctl/host/clock.py: model seconds, on the wall — scaled
for ``sim://?speed=N`` — or virtual).  A ``sim://?clock=virtual`` port has no reader thread: its
clock moves only when a caller waits (``wait``, ``wait_until``, ``idle``), which jumps to the
next status burst through the simulator's virtual-time interface (armctl/host/virtual_wait.py); a
caller that says which frames are news (``wait``'s ``news``: the host driver's, for the job
engine) is woken only by those.  Callers that wait through the link work unchanged on either
kind of port.
"""

from __future__ import annotations

import copy
import errno
import threading
from typing import Callable

from ..core.armstate import ArmState
from .clock import Clock, as_clock
from ..errors import ConfigError, PortError
from .port_choice import PORT_ENV, SIMULATOR_URL, PortChoice, check_port_url, check_sim_url, choose_port, resolve_port  # noqa: F401  (re-exported)
from .profile import check_config_value
from ..core.protocol import DEFAULT_BAUD, STATUS_SIZE, StatusFrame, StatusReader, byte_seconds
from .virtual_wait import UNMERGED_FRAMES_MAX, News, VirtualWaits

READ_CHUNK = 256
READ_TIMEOUT_S = 0.02  # the reader thread wakes this often to notice close()
# On a wall clock the next frame may be handed to the port this long (model seconds) before the
# line is free (``Streamer.write_ahead_s``): a host thread woken late by the OS then still finds the
# line busy, not idle — three frames at 9600 baud, 36 at 115200 (1.7 KB, inside a tty's 4 KB).  At
# 50 ms (one frame at 9600) a machine at load average 8 on 2 cores left one gap of 153 ms in 400
# frames (50.30 ms a frame on average).
WRITE_AHEAD_S = 0.15


def connect(port: "str | PortChoice | None", baud: int | None, announce: Callable[[str], None] | None = None,
            profile=None, **link_options):
    """What every port-using command does first: resolve the port (``--port``, ARMCTL_PORT,
    armctl.toml, the simulator; a ``PortChoice`` is already resolved: ``choose_port``), tell
    ``announce`` (a command's stderr note; None for a library caller, which prints nothing) when
    it is the simulator, open it with a reader thread whose state judges jumps against the arm's
    top speeds (H9). ``profile``: the arm's (``calibration.arm_profile(port=…)``; None: loaded here for the
    port). Returns the link and the baud rate."""
    from .profile import load_config

    from .calibration import arm_profile, with_arm

    config = load_config()
    choice = with_arm(choose_port(port, config))  # (a PortChoice from Arm.open: read already)
    banner = choice.banner()
    if banner and announce is not None:
        announce(banner)
    baud = line_baud(baud, config, choice)[0]
    if profile is None:
        profile = arm_profile(port=choice)
    link_options.setdefault("state", plausible_state(profile))
    return Link.open(choice.url, baud, sim_profile=choice.sim_profile, **link_options), baud


def fifo_proven(url: str, connector) -> bool:
    """``connector.fifo_proven`` for the port at ``url``: a ``sim://`` port says its own FIFO size."""
    options = _sim_options(url)
    return connector.fifo_proven(None if options is None else options.fifo_frames)


def control_frames_proven(url: str, connector) -> bool:
    """``connector.control_frames_proven`` for the port at ``url``: a ``sim://`` port says its own."""
    options = _sim_options(url)
    return connector.control_frames_proven(None if options is None else options.control_frames)


def _sim_options(url: str):
    """What a ``sim://`` port at ``url`` says of itself (None: another port, or options it refuses)."""
    if not url.startswith("sim://"):
        return None
    from ..sim.protocol_sim import parse_sim_url

    try:
        return parse_sim_url(url)
    except ConfigError:
        return None


def require_wall_clock(link: "Link", command: str) -> None:
    """Commands that follow the arm as it moves (a live view, jogging) need time to pass by
    itself; a ``clock=virtual`` simulator only moves when waited on."""
    if link.is_virtual:
        raise ConfigError(f"{command} runs in real time, but {link.url} has a virtual clock: "
                          "use sim:// without clock=virtual")


def config_baud(config: dict, path) -> int:
    return check_config_value(path, "baud", config.get("baud", DEFAULT_BAUD))


def line_baud(baud: int | None, config, port) -> tuple[int, str | None]:
    """The line rate a port-using command talks to the arm on ``port`` (a ``PortChoice``, its arm
    read once, or a URL; None: no port) at, and where it came from (None: the document's 9600):
    ``--baud``, else armctl.toml's ``baud``, else the rate ``armctl probe`` read that arm's status
    at (so a probed 115200 arm needs only ``--port``), else 9600."""
    if baud:
        return baud, "--baud"
    if "baud" in config.values:
        return config_baud(config.values, config.path_of("baud")), str(config.path_of("baud"))
    if port is not None:
        from .calibration import probed_baud

        probed = probed_baud(port)
        if probed is not None:
            return probed
    return DEFAULT_BAUD, None


def plausible_state(profile) -> ArmState:
    """An ArmState that holds back a value moving faster than twice the profile's top speeds
    (a corrupted byte; the profile's numbers are illustrative, hence the factor), the arm's
    ``[connector] speed_factor`` included (0.5: it moves twice as fast as the model)."""
    speed, factor = profile.speed, 2 / min(1.0, profile.connector.speed_factor)
    return ArmState(max_speed_mm_s=factor * speed.max_linear_mm_min / 60,
                    max_joint_speed_deg_s=factor * speed.max_joint_deg_s)


def open_port(url: str, baud: int = DEFAULT_BAUD, timeout: float = READ_TIMEOUT_S, write_timeout: float | None = 2.0,
              sim_profile=None):
    """Open any pyserial URL or device path, mapping failures to PortError.  ``sim_profile``: a
    ``sim://?profile=FILE``'s profile, read already (``PortChoice.sim_profile``): not read again."""
    import serial  # armctl/__init__.py adds the sim:// scheme as pyserial loads

    kwargs = {"baudrate": baud, "timeout": timeout, "write_timeout": write_timeout}
    if sim_profile is not None:
        kwargs["profile"] = sim_profile
    if "://" not in url:
        kwargs["exclusive"] = True  # a second armctl on the same arm would interleave frames
        _refuse_unless_device(url)
    try:
        return serial.serial_for_url(url, **kwargs)
    except ConfigError:  # a bad sim:// option: the user's configuration, not the port
        raise
    except (serial.SerialException, OSError, ValueError) as error:
        raise PortError(describe_open_error(url, error)) from None


def _refuse_unless_device(path: str) -> None:
    """A path that names a file, a directory or a named pipe is said to be one, before pyserial
    opens it read-write and fails in its own words; a missing path is pyserial's to report."""
    import os
    import stat

    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    if not stat.S_ISCHR(mode):
        from .inputs import kind_of

        raise PortError(f"{path} is {kind_of(mode)}, not a serial device: give the arm's port "
                        "(`armctl ports` lists the ports found)")


def describe_open_error(url: str, error: Exception) -> str:
    code = getattr(error, "errno", None)
    text = str(error)
    url = url if url == url.strip() else repr(url)  # ("/dev/ttyUSB0 ": the space at fault, seen)
    if code == errno.ENOENT or "No such file" in text:
        return f"no such device: {url} (is the arm plugged in? `armctl ports` lists the ports found)"
    if code == errno.EACCES or "Permission denied" in text:
        return (
            f"permission denied opening {url}: add yourself to the group that owns it "
            f"(usually `sudo usermod -aG dialout $USER`, then log in again)"
        )
    if code in (errno.EBUSY, errno.EAGAIN) or "exclusively lock" in text:
        return f"{url} is busy: another program (another armctl, a serial monitor) has it open"
    if code == errno.ECONNREFUSED or "Connection refused" in text or "ConnectionRefused" in text:
        return f"connection refused by {url}: is the bridge (e.g. `armctl sim --tcp`) running?"
    return f"cannot open {url}: {text}"


TAKEN_READS_MAX = 8  # a device that is readable with nothing to read more often in a row than this is gone


def bytes_taken(port, error: Exception) -> bool:
    """Whether pyserial's "device reports readiness to read but returned no data" came from a tty
    that is still there: select() said readable, then read() found the bytes gone — taken or
    flushed by another holder of the tty between the two (pyserial opens a port with a flush) —
    and the next read goes on.  A tty that is gone says so to poll(): unplugged, or a
    pseudo-terminal whose other end closed, it is hung up (POLLHUP, POLLERR).  Ports without a
    file descriptor (socket://, sim://) and other errors: False."""
    import select

    descriptor = getattr(port, "fd", None)
    if not isinstance(descriptor, int) or not hasattr(select, "poll") or "returned no data" not in str(error):
        return False
    poller = select.poll()
    poller.register(descriptor, select.POLLIN)
    gone = select.POLLHUP | select.POLLERR | select.POLLNVAL
    try:
        return not any(events & gone for _, events in poller.poll(0))
    except OSError:
        return False


class Link:
    """An open port with a reader thread that keeps ``state`` current.

    ``on_status(frame, now)`` is called from the reader thread (for logs and for the
    streamer); ``error`` is set when the port went away.
    """

    def __init__(
        self,
        port,
        url: str,
        state: ArmState | None = None,
        clock: Callable[[], float] | None = None,
        on_status: Callable[[StatusFrame, float], None] | None = None,
    ) -> None:
        self.port = port
        self.url = url
        # The port's one clock (armctl/host/clock.py); a simulated port on a virtual clock keeps its
        # own, which only waiting moves, whatever clock is passed.
        virtual = getattr(port, "virtual_clock", None)
        self.clock: Clock = virtual or (port_clock(port, url) if clock is None else as_clock(clock))
        self.reader = StatusReader()
        self._state = state or ArmState()
        # Frames read by virtual waits, merged into the state when it is read (``state``): nothing
        # reads it while a job runs, and the kinds taken as read then cost one merge, not one a
        # frame (``ArmState.update_many``); at most ``UNMERGED_FRAMES_MAX`` held (a long job).
        self.unmerged: list = []
        self.on_status = on_status
        self.bytes_received = 0
        self.error: PortError | None = None
        self.lock = self._changed = threading.Condition()
        self._virtual = VirtualWaits(self) if self.clock.virtual else None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._read_loop, name="armctl-reader", daemon=True)

    @classmethod
    def open(cls, url: str, baud: int = DEFAULT_BAUD, sim_profile=None, **kwargs) -> "Link":
        link = cls(open_port(url, baud, sim_profile=sim_profile), url, **kwargs)
        link.start()
        return link

    def start(self) -> None:
        if not self.clock.virtual:
            self._thread.start()

    @property
    def state(self) -> ArmState:
        """What the arm last told us (the frames of virtual runs merged first)."""
        if self.unmerged:
            self._merge()
        return self._state

    @state.setter
    def state(self, state: ArmState) -> None:
        with self._changed:
            self.unmerged.clear()
            self._state = state

    def _merge(self) -> None:
        with self._changed:
            self._state.update_many(self.unmerged)
            self.unmerged.clear()  # (in place: a run in progress keeps appending to it)

    @property
    def is_virtual(self) -> bool:
        return self.clock.virtual

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=1.0)
        try:
            self.port.close()
        except Exception:  # closing a port that vanished may fail again; nothing to do
            pass

    def __enter__(self) -> "Link":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _read_loop(self) -> None:
        port = self.port
        taken_in_a_row = 0  # reads in a row that found the bytes taken (``bytes_taken``)
        while not self._stop.is_set():
            try:
                # A status frame's bytes, then whatever else is waiting: each frame is taken (and
                # timed) as it completes, not when a bigger read's timeout runs out (a read of 256
                # bytes timed the frames up to READ_TIMEOUT_S late, two at a time).
                data = port.read(STATUS_SIZE)
                waiting = getattr(port, "in_waiting", 0) if data else 0
                if waiting:
                    data += port.read(min(waiting, READ_CHUNK))
            except Exception as error:  # pyserial raises SerialException, OSError or TypeError on unplug
                if self._stop.is_set():
                    return
                taken_in_a_row += 1
                if taken_in_a_row <= TAKEN_READS_MAX and bytes_taken(port, error):
                    continue
                self._set_error(PortError(f"the port {self.url} went away: {error}"))
                return
            taken_in_a_row = 0
            if data:
                self.take(data)

    def take(self, data: bytes, news: News | None = None) -> bool:
        """Feed bytes read to the status reader and the state; whether a frame was found — with
        ``news`` (a virtual wait's burst), whether one of them was news to it
        (it takes every frame found: it is asked again with those after the one it named; the
        state merges them when it is read, as a run's)."""
        now = self.clock()
        frames = self.reader.feed(data)
        if news is not None:
            return self._take_news(frames, now, len(data), news)
        with self._changed:
            self.bytes_received += len(data)
            update, on_status = self.state.update, self.on_status
            for frame in frames:
                update(frame, now)
                if on_status is not None:
                    on_status(frame, now)
            if not self.clock.virtual:  # a virtual link's waits run the simulator: nobody sleeps on it
                self._changed.notify_all()
        return bool(frames)

    def _take_news(self, frames: list, now: float, received_bytes: int, news: News) -> bool:
        """``take``'s frames of a virtual wait: held for the state, every one handed to ``news``."""
        with self._changed:
            self.bytes_received += received_bytes
            if not frames:
                return False
            self.unmerged += [(frame, now) for frame in frames]
            if len(self.unmerged) >= UNMERGED_FRAMES_MAX:
                self._merge()
        if len(frames) == 1:
            return news(frames, [now]) is not None
        found, start = False, 0
        while start < len(frames):
            rest = frames[start:]
            place = news(rest, [now] * len(rest))
            if place is None:
                break
            found, start = True, start + place + 1
        return found

    def counted(self, frames: int, received_bytes: int) -> None:
        """Frames read by a virtual run (``unmerged``, lock held): the counts, the merge when many."""
        self.reader.frames += frames
        self.bytes_received += received_bytes
        if len(self.unmerged) >= UNMERGED_FRAMES_MAX:
            self._merge()

    def idle(self, seconds: float) -> None:
        """Wait up to ``seconds`` of the link's clock; returns early once a status frame has
        been read.  (On a real port the reader thread reads meanwhile; this only waits.)"""
        self.wait(self.clock.now() + seconds)

    def wait(self, until_s: float | None, news: News | None = None) -> None:
        """Wait until the clock reads ``until_s`` (None: no limit) or a status frame has been
        read, whichever comes first.  On a virtual clock this jumps: straight to the next
        status burst or to ``until_s`` (armctl/host/virtual_wait.py); ``news(frames, times)`` (the
        place of the first frame that is news, or None) then takes the frames instead of
        ``on_status``, and a frame that is not news does not end the wait — the link drives the
        simulator on, burst after burst, without returning to a caller that has nothing new to
        decide (the host driver).  On a wall clock the reader thread hands frames to
        ``on_status`` and ``news`` is not used."""
        if self._virtual is not None:
            self._virtual.wait(until_s, news)
            return
        # A timer for ``until_s`` itself (the reader thread's notify ends it sooner): a write
        # due then goes then, not at the next status frame or poll (a 20 ms poll made every
        # frame of a line-bound job 11 ms late on average: 61 ms a frame at 9600 baud).
        clock = self.clock
        with self._changed:
            frames = self.reader.frames
            while self.reader.frames == frames and self.error is None:
                if until_s is None:
                    self._changed.wait(READ_TIMEOUT_S)
                    continue
                left_s = until_s - clock.now()
                if left_s <= 0:
                    break
                self._changed.wait(clock.wall_seconds(left_s))

    def _set_error(self, error: PortError) -> None:
        with self._changed:
            self.error = error
            self._changed.notify_all()

    def write(self, frame: bytes) -> None:
        if self._virtual is not None:
            self._virtual.forget()  # the simulator's next steps change
        if self.error is not None:
            raise self.error
        try:
            self.port.write(frame)
        except Exception as error:
            raise PortError(f"writing to {self.url} failed: {error}") from None

    def unsent_s(self) -> float | None:
        """Model seconds until the bytes the port still holds have left it (its ``out_waiting``
        at its baud rate), or None where the port cannot say (a socket, a fake)."""
        port = self.port
        try:
            waiting = port.out_waiting
            baud = port.baudrate
        except Exception:  # (AttributeError, NotImplementedError, OSError: no such ioctl)
            return None
        if not isinstance(waiting, int) or not isinstance(baud, int) or baud <= 0:
            return None
        return waiting * byte_seconds(baud)

    def silence_message(self, timeout_s: float) -> str:
        """Why the status was not complete within ``timeout_s``, and what to check — the one
        wording of it (``armctl status``, a job's start, ``Arm.status()``): nothing heard (power,
        cable), bytes that never formed a status frame (the baud rate: an arm at another rate sends
        just that), or the kinds never seen."""
        from ..core.protocol import STATUS_KINDS, STATUS_ROTATION

        state, received, skipped, frames = self.snapshot()
        baud = getattr(self.port, "baudrate", None)
        rate = f" at {baud} baud" if isinstance(baud, int) else ""
        where = f"no complete status from {self.url}{rate} within {timeout_s:g} s"
        if received == 0:
            return f"{where}: received nothing (is the arm powered and the cable on the host connector?)"
        if frames == 0:
            return (f"{where}: received {received} bytes that never formed a status frame "
                    f"({skipped} skipped; is the baud rate right?)")
        missing = [STATUS_KINDS[k].NAME for k in STATUS_ROTATION if k not in state.last_seen]
        return f"{where}: {frames} status frames read, never saw: {', '.join(missing)}"

    def snapshot(self) -> tuple[ArmState, int, int, int]:
        """A copy of the state with bytes received, bytes skipped and frames read so far."""
        with self._changed:
            return copy.deepcopy(self.state), self.bytes_received, self.reader.skipped_bytes, self.reader.frames

    def wait_until(self, predicate: Callable[[ArmState], bool], timeout_s: float) -> bool:
        """Block until ``predicate(state)`` holds, the port fails (raises) or time runs out."""
        deadline = self.clock() + timeout_s
        if self.clock.virtual:
            while not predicate(self.state):
                if self.clock() >= deadline:
                    return False
                self.idle(deadline - self.clock())
            return True
        with self._changed:
            while not predicate(self.state):
                if self.error is not None:
                    raise self.error
                remaining = deadline - self.clock()
                if remaining <= 0:
                    return False
                self._changed.wait(min(remaining, 0.05))
            return True



def port_clock(port, url: str) -> Clock:
    """The clock of an opened port: the simulator's virtual clock, else the wall × the
    ``sim://`` speed (1 for any other port)."""
    virtual = getattr(port, "virtual_clock", None)
    if virtual is not None:
        return virtual
    return Clock(sim_time_scale(url))


def sim_time_scale(url: str) -> float:
    """``sim://?speed=N``'s N (1 for any other port); the one parse is protocol_sim's."""
    if not url.startswith("sim://"):
        return 1.0
    from ..sim.protocol_sim import parse_sim_url

    return parse_sim_url(url).time_scale
