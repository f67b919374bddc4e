"""The port edge: choose a port, open it, read status frames in a thread, write frames.

Strategy (after pyserial and python-can): every port is a pyserial URL — a device path,
``socket://``, ``rfc2217://`` or armctl's own ``sim://`` — opened with ``serial_for_url``, so
nothing above this module knows whether a real arm is attached.  A reader thread feeds bytes
to the pure ``StatusReader`` and merges frames into an ``ArmState`` under a lock; callers take
snapshots or wait on a condition.  OS failures become ``PortError`` with a sentence a user can
act on (no such device, permission denied with the dialout hint, busy, vanished).

The link owns the port's one ``Clock`` (armctl/clock.py: model seconds, on the wall — scaled
for ``sim://?speed=N`` — or virtual).  A ``sim://?clock=virtual`` port has no reader thread: its
clock moves only when a caller waits (``wait``, ``wait_until``, ``idle``), which jumps to the
next status burst and reads it at the model time it lands (``Serial.step_virtual``: the
simulator driven directly, no wall-clock machinery); a caller whose ``on_status`` says which
frames are news (the job runner) is woken only by those, and the simulator's quiet stretches
(nothing happens in it but status frames) are then read as runs of steps timed ahead
(``Serial.virtual_status_run``), their frames built and decoded a batch at a time and the
run committed as far as it was read: the same frames at the same model times, without the
per-burst machinery.  The steps of a run past the frame that was news, and the frames built
for them, stay the simulator's next while nothing else touches the port (the run's arithmetic
from the committed state is the same from any step on; a quiet stretch changes nothing a
frame is built from): the next news-only wait that starts where that frame was read reads
them (cut at its own end) instead of timing and building them again, and a write forgets
them — at most a batch of frames built for nothing a write.  Callers that wait through the
link work unchanged on either kind of port.
"""

from __future__ import annotations

import copy
import errno
import threading
from typing import Callable

from .armstate import ArmState
from .clock import Clock, as_clock, port_clock
from .errors import ConfigError, PortError
from .port_choice import PORT_ENV, SIMULATOR_URL, PortChoice, check_sim_url, choose_port, resolve_port  # noqa: F401  (re-exported)
from .profile import check_config_value
from .protocol import DEFAULT_BAUD, STATUS_SIZE, StatusFrame, StatusReader, byte_seconds

READ_CHUNK = 256
READ_TIMEOUT_S = 0.02  # the reader thread wakes this often to notice close()
VIRTUAL_MIN_STEP_S = 1e-6
VIRTUAL_READ_CHUNK = 1 << 16  # more than any burst between two waits
# A virtual wait reads the simulator's quiet stretches as runs of steps timed ahead
# (``Serial.virtual_status_run``), from this many, doubling while no frame is news, up to the
# most.  The steps past the news are kept for the next wait (``Link._run_tail``) and thrown
# away only when something else touches the port (a write): 32 measured best of 8…512 for the
# 20-minute job of benchmarks/virtual_run.py (8 was best before the steps were kept).
VIRTUAL_RUN_FRAMES_MIN = 32
VIRTUAL_RUN_FRAMES_MAX = 512
# The frames of a run are built and decoded this many at a time, ahead of reading them: the
# simulator's code and the engine's each run in a batch (the 20-minute job: 0.82 -> 0.75 s of
# CPU), and a write wastes at most this many builds (the tail it forgets).
VIRTUAL_BUILD_FRAMES = 64
# On a wall clock the next frame may be handed to the port this long (model seconds) before the
# line is free (``Streamer.write_ahead_s``): a host thread woken late by the OS then still finds the
# line busy, not idle — three frames at 9600 baud, 36 at 115200 (1.7 KB, inside a tty's 4 KB).  At
# 50 ms (one frame at 9600) a machine at load average 8 on 2 cores left one gap of 153 ms in 400
# frames (50.30 ms a frame on average).
WRITE_AHEAD_S = 0.15
UNMERGED_FRAMES_MAX = 4096  # frames of virtual runs held before they are merged into the state


def connect(port: "str | PortChoice | None", baud: int | None, announce: Callable[[str], None] | None = None,
            profile=None, **link_options):
    """What every port-using command does first: resolve the port (``--port``, ARMCTL_PORT,
    armctl.toml, the simulator; a ``PortChoice`` is already resolved: ``choose_port``), tell
    ``announce`` (a command's stderr note; None for a library caller, which prints nothing) when
    it is the simulator, open it with a reader thread whose state judges jumps against the arm's
    top speeds (H9). ``profile``: the arm's (``calibration.arm_profile(port=…)``; None: loaded here for the
    port). Returns the link and the baud rate."""
    from .profile import load_config

    config = load_config()
    choice = choose_port(port, config)
    banner = choice.banner()
    if banner and announce is not None:
        announce(banner)
    baud = baud or config_baud(config.values, config.path_of("baud"))
    if profile is None:
        from .calibration import arm_profile

        profile = arm_profile(port=choice.url)
    link_options.setdefault("state", plausible_state(profile))
    return Link.open(choice.url, baud, **link_options), baud


def fifo_proven(url: str, connector) -> bool:
    """``connector.fifo_proven`` for the port at ``url``: a ``sim://`` port says its own FIFO size."""
    port_fifo_frames = None
    if url.startswith("sim://"):
        from .sim.protocol_sim import parse_sim_url

        try:
            port_fifo_frames = parse_sim_url(url).fifo_frames
        except ConfigError:
            pass
    return connector.fifo_proven(port_fifo_frames)


def require_wall_clock(link: "Link", command: str) -> None:
    """Commands that follow the arm as it moves (a live view, jogging) need time to pass by
    itself; a ``clock=virtual`` simulator only moves when waited on."""
    if link.is_virtual:
        raise ConfigError(f"{command} runs in real time, but {link.url} has a virtual clock: "
                          "use sim:// without clock=virtual")


def config_baud(config: dict, path) -> int:
    return check_config_value(path, "baud", config.get("baud", DEFAULT_BAUD))


def plausible_state(profile) -> ArmState:
    """An ArmState that holds back a value moving faster than twice the profile's top speeds
    (a corrupted byte; the profile's numbers are illustrative, hence the factor), the arm's
    ``[connector] speed_factor`` included (0.5: it moves twice as fast as the model)."""
    speed, factor = profile.speed, 2 / min(1.0, profile.connector.speed_factor)
    return ArmState(max_speed_mm_s=factor * speed.max_linear_mm_min / 60,
                    max_joint_speed_deg_s=factor * speed.max_joint_deg_s)


def open_port(url: str, baud: int = DEFAULT_BAUD, timeout: float = READ_TIMEOUT_S, write_timeout: float | None = 2.0):
    """Open any pyserial URL or device path, mapping failures to PortError."""
    import serial  # armctl/__init__.py adds the sim:// scheme as pyserial loads

    kwargs = {"baudrate": baud, "timeout": timeout, "write_timeout": write_timeout}
    if "://" not in url:
        kwargs["exclusive"] = True  # a second armctl on the same arm would interleave frames
    try:
        return serial.serial_for_url(url, **kwargs)
    except ConfigError:  # a bad sim:// option: the user's configuration, not the port
        raise
    except (serial.SerialException, OSError, ValueError) as error:
        raise PortError(describe_open_error(url, error)) from None


def describe_open_error(url: str, error: Exception) -> str:
    code = getattr(error, "errno", None)
    text = str(error)
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
        # The port's one clock (armctl/clock.py); a simulated port on a virtual clock keeps its
        # own, which only waiting moves, whatever clock is passed.
        virtual = getattr(port, "virtual_clock", None)
        self.clock: Clock = virtual or (port_clock(port, url) if clock is None else as_clock(clock))
        self.reader = StatusReader()
        self._state = state or ArmState()
        # Frames read by virtual runs, merged into the state when it is read (``state``): nothing
        # reads it while a job runs, and the kinds taken as read then cost one merge, not one a
        # frame (``ArmState.update_many``); at most ``UNMERGED_FRAMES_MAX`` held (a long job).
        self._unmerged: list = []
        self.on_status = on_status
        # ``on_status`` for a batch of frames at once (virtual runs, ``_take_run``): the place of
        # the first that is news, or None (``JobRunner.on_status_run``); set with ``on_status``
        self.on_status_run: Callable[[list, list], int | None] | None = None
        self.bytes_received = 0
        # The unread steps of the last status run (the run, the first unread, the clock time of
        # the last read, the frames built for it so far): still the simulator's next steps while
        # nothing else touched the port and the clock is where that run left it (``wait``;
        # ``write`` forgets them)
        self._run_tail: tuple[list, int, float, list] | None = None
        self.error: PortError | None = None
        self._changed = threading.Condition()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._read_loop, name="armctl-reader", daemon=True)

    @classmethod
    def open(cls, url: str, baud: int = DEFAULT_BAUD, **kwargs) -> "Link":
        link = cls(open_port(url, baud), url, **kwargs)
        link.start()
        return link

    def start(self) -> None:
        if not self.clock.virtual:
            self._thread.start()

    @property
    def state(self) -> ArmState:
        """What the arm last told us (the frames of virtual runs merged first)."""
        if self._unmerged:
            self._merge()
        return self._state

    @state.setter
    def state(self, state: ArmState) -> None:
        with self._changed:
            self._unmerged.clear()
            self._state = state

    def _merge(self) -> None:
        with self._changed:
            self._state.update_many(self._unmerged)
            self._unmerged.clear()  # (in place: a run in progress keeps appending to it)

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
                if not self._stop.is_set():
                    self._set_error(PortError(f"the port {self.url} went away: {error}"))
                return
            if data:
                self._take(data)

    def _take(self, data: bytes, news_only: bool = False) -> int:
        """Feed bytes read to the status reader and the state; the number of frames found — with
        ``news_only``, less those ``on_status`` answered False for (a frame that cannot change
        what its caller does next)."""
        now = self.clock()
        frames = self.reader.feed(data)
        news = 0
        with self._changed:
            self.bytes_received += len(data)
            update, on_status = self.state.update, self.on_status
            for frame in frames:
                update(frame, now)
                if on_status is None or on_status(frame, now) is not False or not news_only:
                    news += 1
            if not self.clock.virtual:  # a virtual link's waits run the simulator: nobody sleeps on it
                self._changed.notify_all()
        return news

    def idle(self, seconds: float) -> None:
        """Wait up to ``seconds`` of the link's clock; returns early once a status frame has
        been read.  (On a real port the reader thread reads meanwhile; this only waits.)"""
        self.wait(self.clock.now() + seconds)

    def wait(self, until_s: float | None, news_only: bool = False) -> None:
        """Wait until the clock reads ``until_s`` (None: no limit) or a status frame has been
        read, whichever comes first.  On a virtual clock this jumps: straight to the next
        status burst or to ``until_s``, and at least a microsecond (a wait computed as a
        difference of nearly equal floats could otherwise leave the clock where it is, and
        the caller asking again forever).  ``news_only`` (virtual clock): a frame ``on_status``
        answers False for does not end the wait — the link drives the simulator on, burst after
        burst, without returning to a caller that has nothing new to decide (runner.py)."""
        clock = self.clock
        if not clock.virtual:
            # A timer for ``until_s`` itself (the reader thread's notify ends it sooner): a write
            # due then goes then, not at the next status frame or poll (a 20 ms poll made every
            # frame of a line-bound job 11 ms late on average: 61 ms a frame at 9600 baud).
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
            return
        end_s = max(until_s, clock.now_s + VIRTUAL_MIN_STEP_S) if until_s is not None else None
        port = self.port
        step, take = port.step_virtual, self._take
        status_run = getattr(port, "virtual_status_run", None) if news_only else None
        run_frames = VIRTUAL_RUN_FRAMES_MIN
        tail, self._run_tail = self._run_tail, None
        while True:  # burst after burst until one holds news for on_status, or end_s
            if status_run is not None:
                built = None
                if tail is not None and tail[2] == clock.now_s:
                    run = _steps_by(tail[0], tail[1], end_s)
                    built = tail[3][tail[1]:tail[1] + len(run)]
                else:
                    run = status_run(end_s, VIRTUAL_MIN_STEP_S, run_frames)
                tail = None
                if run:
                    read, news = self._take_run(run, built)
                    if news or (end_s is not None and clock.now_s >= end_s):
                        return
                    if read == len(run):
                        run_frames = min(2 * run_frames, VIRTUAL_RUN_FRAMES_MAX)  # quiet: look further ahead
                        continue
                    # a frame the run could not decode (never on a clean line): the ordinary way reads it
            data = step(end_s, VIRTUAL_MIN_STEP_S, VIRTUAL_READ_CHUNK)
            if (data and take(data, news_only)) or (end_s is not None and clock.now_s >= end_s):
                return

    def _take_run(self, run: list, built: list | None = None) -> tuple[int, bool]:
        """A run of quiet steps computed ahead by the simulator (``virtual_status_run``: one
        status frame each, with the clock time it is read at), read as ``wait`` reads them one
        burst at a time — the clock at the frame's time, the frame (built by ``status_frames``
        and decoded by ``StatusReader.decode_frame``, ``VIRTUAL_BUILD_FRAMES`` at a time; the
        first ones may be ``built`` already), the state, ``on_status`` — stopping after the
        first frame that is news to ``on_status`` (a run never goes past the wait's end).  The
        frames read are committed to the simulator whatever happens (``on_status`` may raise:
        Ctrl-C), so none is read twice.  With ``on_status_run`` set, the frames built go to it a
        batch at a time (the engine takes them in one call: ``JobRunner.on_status_run``), the
        clock moved to the last one it took; when it raises, every frame it was given counts as
        read.  Returns (frames read, whether the last was news)."""
        port, clock, reader, on_status, unmerged = self.port, self.clock, self.reader, self.on_status, self._unmerged
        build, decode = port.status_frames, reader.decode_frames
        advance = clock.advance_to
        read = 0
        try:
            with self._changed:
                try:
                    built = [] if built is None else built
                    on_status_run = self.on_status_run if on_status is not None else None
                    while on_status_run is not None:  # the frames built, a batch at a time
                        if read == len(run):
                            return read, False
                        if read == len(built):
                            batch = build(run[read:read + VIRTUAL_BUILD_FRAMES])
                            decoded = decode(batch)
                            built += decoded
                            if len(decoded) < len(batch):  # cannot happen on a clean line: the ordinary way reads it
                                built.append(None)
                        frames = built[read:]
                        whole = built[-1] is not None
                        if not whole:
                            frames.pop()
                            if not frames:
                                return read, False
                        times = [step[0] for step in run[read:read + len(frames)]]
                        news = len(frames) - 1  # if it raises: the engine had them all, or is gone
                        try:
                            news = on_status_run(frames, times)
                        finally:
                            taken = len(frames) if news is None else news + 1
                            advance(times[taken - 1])
                            read += taken
                            unmerged += zip(frames, times[:taken])  # merged into the state when it is read
                        if news is not None:
                            if read < len(run):
                                self._run_tail = (run, read, times[taken - 1], built)
                            return read, True
                        if not whole:
                            return read, False
                    for at_s, _, _, _, _ in run:
                        if read == len(built):  # the next frames built and decoded a batch at a time
                            batch = build(run[read:read + VIRTUAL_BUILD_FRAMES])
                            decoded = decode(batch)
                            built += decoded
                            if len(decoded) < len(batch):
                                built.append(None)
                        frame = built[read]
                        if frame is None:  # cannot happen on a clean line: the ordinary way reads it
                            break
                        advance(at_s)
                        read += 1
                        unmerged.append((frame, at_s))  # merged into the state when it is read
                        if on_status is None or on_status(frame, at_s) is not False:
                            if read < len(run):
                                self._run_tail = (run, read, at_s, built)
                            return read, True
                    return read, False
                finally:  # the counts for the whole run at once, before the lock is let go
                    reader.frames += read
                    self.bytes_received += read * STATUS_SIZE
                    if len(unmerged) >= UNMERGED_FRAMES_MAX:
                        self._merge()
        finally:
            port.commit_status_run(run, read)

    def _set_error(self, error: PortError) -> None:
        with self._changed:
            self.error = error
            self._changed.notify_all()

    def write(self, frame: bytes) -> None:
        self._run_tail = None  # the simulator's next steps change
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


def _steps_by(run: list, start: int, end_s: float | None) -> list:
    """The steps of ``run`` from ``start`` on that end by ``end_s`` (their clock times grow)."""
    stop = len(run)
    if end_s is not None:
        for k in range(start, stop):
            if run[k][0] > end_s:
                stop = k
                break
    return run[start:stop]
