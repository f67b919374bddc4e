"""``sim://`` — the simulated arm as a pyserial port (after pyserial's ``protocol_loop.py``).

URL: ``sim://[?option=value&…]``, options (all optional):

====================  ===============================================================  =========
option                meaning                                                          default
====================  ===============================================================  =========
speed                 time scale: 4 = the arm runs 4× faster than the wall clock       1
clock                 ``wall``, or ``virtual``: model time moves only while armctl     wall
                      waits on the port (``run``, ``status`` without ``--watch``), so
                      a job takes milliseconds and runs identically on any machine
fifo_frames           frames the connector accepts behind the one executing (alias     200
                      ``fifo``)
control_frames        ``queued`` (H5: control frames wait in the FIFO) or ``arrival``   queued
                      (alias ``control``)
status_xyz_frame      ``worktable`` or ``robot``: the frame of status kind 0's X/Y/Z    worktable
                      after G54
speed_factor          the arm's real motion time ÷ the model's: 1.3 = every motion     1
                      takes 30 % longer than commanded (alias ``slowdown``)
link_scale            the arm's link lengths are the profile's × this: its reported   1
                      joints and X/Y/Z disagree with the profile's kinematics
status_jitter_ms      each status frame is built up to this many ms after its place     0
                      on the period (uniform, from ``seed``)
baud                  the arm's line rate in bit/s (else the port's ``baudrate``); a   9600
                      port set to another rate hears noise and the arm nothing
loss                  share of status frames lost                                      0
corrupt               share of status frames with one byte flipped                     0
noise                 share of status frames preceded by random noise bytes            0
seed                  seed of the faults                                               0
profile               path of an arm profile (TOML)                                    built-in
write_buffer_bytes    host bytes held before the wire (a tty's buffer): ``write``      none
                      blocks while it is full (``write_timeout`` applies)
read_granularity_ms   status bytes reach the host only at ticks this many ms apart     0
                      (a USB adapter's latency timer; wall clock only)
====================  ===============================================================  =========

The first four after ``clock``, and ``status_jitter_ms``, are the arm profile's ``[connector]``
settings under the same names: the simulated arm impersonates any arm a profile may describe (its profile's own
``[connector]`` table is the host's belief and is not read here).

A port opened at another rate than the arm's ``baud`` is a line set wrong, as on a real arm: the
arm hears nothing it can frame (the bytes written are lost) and the host reads noise — as many
bytes as the arm's status at the port's rate would give, never a status frame's first byte, so
armctl says to check the baud rate (``LineNoise``).  The port keeps the rate it was set to.

Each number has a finite range (armctl/core/limits.py, also in the README); an unknown option, a
bad or out-of-range value is a ``SimOptionError`` naming the option: a ``ConfigError`` for
armctl (exit 2 on every command) and a ``SerialException`` for any other pyserial program.
``parse_sim_url`` is the one parse of the URL, into one ``SimOptions`` (time scale and clock
included); everything else calls it.

Strategy: a thin edge.  With ``clock=virtual`` nothing blocks: ``read`` returns what has
arrived by the current model time, and the host moves the clock instead of sleeping, through
the virtual-time interface: ``next_event_s`` (when the next status burst has reached the host),
``advance_to(t)`` (the clock there, the bytes that arrived) and, for the quiet stretches where
nothing happens but status frames, ``virtual_status_run`` / ``status_frames`` /
``commit_status_run`` (armctl/host/virtual_wait.py drives them).  Otherwise:  ``write`` hands the bytes to the model at the current model time and
returns at once (they queue on the simulated wire; ``out_waiting`` counts those not yet sent);
``read`` runs the model up to now and, while it lacks bytes, sleeps until the next status byte
is due — on an ``Event``, so ``close``/``cancel_read`` wake it — never busy-waiting.  All model
access goes through ``RealtimeArm``'s lock.  ``.model`` is the ``SimulatedArm`` for tests.
Registered by importing ``armctl.sim`` (it appends itself to
``serial.protocol_handler_packages``).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import threading
import time
import urllib.parse
from typing import Callable

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, SerialTimeoutException, to_bytes

from ..errors import ConfigError
from ..core.limits import (BAUD_RANGE, SIM_FIFO_RANGE_FRAMES, SIM_LINK_SCALE_RANGE, SIM_RATE_RANGE,
                           STATUS_JITTER_RANGE_MS,
                      SIM_READ_GRANULARITY_RANGE_MS, SIM_SEED_RANGE, SIM_SLOWDOWN_RANGE, SIM_TIME_SCALE_RANGE,
                      SIM_WRITE_BUFFER_RANGE_BYTES)
from .model import SimOptions, SimulatedArm
from .realtime import RealtimeArm, VirtualClock

_USAGE = (
    "expected sim://[?option=value&…] with options speed, clock=wall|virtual, fifo_frames, "
    "control_frames=queued|arrival, status_xyz_frame=worktable|robot, speed_factor, link_scale, status_jitter_ms, baud, "
    "loss, corrupt, noise, seed, profile, write_buffer_bytes, read_granularity_ms"
)


class SimOptionError(ConfigError, SerialException):
    """A bad ``sim://`` URL: a usage error for armctl (exit 2), a ``SerialException`` for any
    program that opens the URL through pyserial."""


def _shown(text: str, limit: int = 60) -> str:
    """``text`` quoted for a message, cut short: a URL may be any length."""
    return repr(text) if len(text) <= limit else repr(text[: limit - 1]) + "…"


def _float_in(low: float, high: float) -> Callable[[str, str], float]:
    def parse(name: str, text: str) -> float:
        try:
            # ASCII only: float() also reads other scripts' digits ("١" is 1), which nobody means in a URL
            value = float(text) if text.isascii() else math.nan
        except ValueError:
            value = math.nan
        # NaN fails every comparison, so "not inside" also refuses it (and ±inf)
        if not low <= value <= high:
            raise ValueError(f"{name} must be a number {low:g}…{high:g}, not {_shown(text)}")
        return value

    return parse


def _int_in(low: int, high: int) -> Callable[[str, str], int]:
    def parse(name: str, text: str) -> int:
        digits = text.strip()
        # bounded length first: int() of a 100,000-digit text costs time and may refuse itself
        plain = digits.isascii() and digits.lstrip("+-").isdigit()  # "١" is a digit to isdigit(), not in a URL
        value = int(digits) if len(digits) <= 25 and plain else None
        if value is None or not low <= value <= high:
            raise ValueError(f"{name} must be a whole number {low}…{high}, not {_shown(text)}")
        return value

    return parse


def _one_of(*choices: str) -> Callable[[str, str], str]:
    def parse(name: str, text: str) -> str:
        if text not in choices:
            raise ValueError(f"{name} must be {' or '.join(map(repr, choices))}, not {_shown(text)}")
        return text

    return parse


def _clock(name: str, text: str) -> bool:
    return _one_of("wall", "virtual")(name, text) == "virtual"


def _path(name: str, text: str) -> str:
    if not text:
        raise ValueError(f"{name} must be the path of a profile TOML, not ''")
    return text


def _ms_as_s(low_ms: float, high_ms: float) -> Callable[[str, str], float]:
    milliseconds = _float_in(low_ms, high_ms)
    return lambda name, text: milliseconds(name, text) / 1000.0


_FIFO = _int_in(*SIM_FIFO_RANGE_FRAMES)
_CONTROL = _one_of("queued", "arrival")
_SPEED_FACTOR = _float_in(*SIM_SLOWDOWN_RANGE)
# URL option → (SimOptions field, parser), the one table of options (the docstring's table says
# what each means); ranges from armctl/core/limits.py.  An alias names the same field as the option
# it stands for (the old short names, kept working).
_OPTIONS: dict[str, tuple[str, Callable[[str, str], object]]] = {
    "speed": ("time_scale", _float_in(*SIM_TIME_SCALE_RANGE)),
    "clock": ("virtual_clock", _clock),
    "fifo_frames": ("fifo_frames", _FIFO),
    "control_frames": ("control_frames", _CONTROL),
    "status_xyz_frame": ("status_xyz_frame", _one_of("worktable", "robot")),
    "speed_factor": ("speed_factor", _SPEED_FACTOR),
    "link_scale": ("link_scale", _float_in(*SIM_LINK_SCALE_RANGE)),
    "status_jitter_ms": ("status_jitter_s", _ms_as_s(*STATUS_JITTER_RANGE_MS)),
    "baud": ("baud", _int_in(*BAUD_RANGE)),
    "loss": ("status_loss_rate", _float_in(*SIM_RATE_RANGE)),
    "corrupt": ("status_corrupt_rate", _float_in(*SIM_RATE_RANGE)),
    "noise": ("noise_rate", _float_in(*SIM_RATE_RANGE)),
    "seed": ("seed", _int_in(*SIM_SEED_RANGE)),
    "profile": ("profile", _path),
    "write_buffer_bytes": ("write_buffer_bytes", _int_in(*SIM_WRITE_BUFFER_RANGE_BYTES)),
    "read_granularity_ms": ("read_granularity_s", _ms_as_s(*SIM_READ_GRANULARITY_RANGE_MS)),
    "fifo": ("fifo_frames", _FIFO),  # alias of fifo_frames
    "control": ("control_frames", _CONTROL),  # alias of control_frames
    "slowdown": ("speed_factor", _SPEED_FACTOR),  # alias of speed_factor
}
OPTION_NAMES = tuple(_OPTIONS)


def parse_sim_url(url: str, baud: int | None = None) -> SimOptions:
    """Everything a ``sim://`` URL asks for, time scale and clock included (``baud``: the port's
    rate, unless the URL names one); SimOptionError if the URL is bad."""
    try:
        parts = urllib.parse.urlsplit(url)
    except ValueError as error:  # "sim://[": an unclosed IPv6 host ("Invalid IPv6 URL")
        raise SimOptionError(f"{_shown(url)} is not a URL ({error}; {_USAGE})") from None
    if parts.scheme != "sim":
        raise SimOptionError(f"{_shown(url)} does not start with sim:// ({_USAGE})")
    if parts.netloc or parts.path.strip("/") or parts.fragment:
        raise SimOptionError(f"{_shown(url)}: sim:// takes its options after '?', nothing else ({_USAGE})")
    values: dict = {}
    named: dict[str, str] = {}  # field → the option that set it (an option and its alias clash)
    try:
        for name, texts in urllib.parse.parse_qs(parts.query, keep_blank_values=True).items():
            if name not in _OPTIONS:
                close = difflib.get_close_matches(name, OPTION_NAMES, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise ValueError(f"unknown option {_shown(name)}{hint}")
            if len(texts) > 1:
                raise ValueError(f"option {name!r} is given {len(texts)} times")
            target, parse = _OPTIONS[name]
            if target in named:
                raise ValueError(f"options {named[target]!r} and {name!r} both set {target}")
            named[target] = name
            values[target] = parse(name, texts[0])
        if values.get("virtual_clock") and values.get("time_scale", 1.0) != 1.0:
            raise ValueError("speed has no meaning with clock=virtual (the clock waits for nobody)")
        if values.get("virtual_clock") and values.get("read_granularity_s", 0.0):
            raise ValueError("read_granularity_ms has no meaning with clock=virtual (its reads take each burst as it lands)")
        if baud is not None:
            values.setdefault("baud", baud)
        return SimOptions(**values)
    except ValueError as error:
        raise SimOptionError(f"{error} in {_shown(url)} ({_USAGE})") from None


class LineNoise:
    """What a port set to ``port_baud`` reads of an arm sending at ``arm_baud``: each of the arm's
    bytes spans ``port_baud / arm_baud`` of the port's byte times, so about that many bytes of
    noise (at least one a burst: the line was not idle), from ``seed``, none of them a status
    frame's first byte (a frame would otherwise start in the noise now and then, which a real
    line at the wrong rate seldom gives and the reader's checks would mostly refuse anyway)."""

    def __init__(self, port_baud: int, arm_baud: int, seed: int) -> None:
        import random

        from ..core.frame_fields import STATUS_HEAD

        self._ratio = port_baud / arm_baud
        self._owed = 0.0
        self._random = random.Random(seed)
        self._bytes = bytes(b for b in range(256) if b != STATUS_HEAD)

    def heard(self, data: bytes) -> bytes:
        if not data:
            return b""
        self._owed += len(data) * self._ratio
        count = max(1, int(self._owed))
        self._owed = max(0.0, self._owed - count)
        return bytes(self._random.choice(self._bytes) for _ in range(count))


class Serial(SerialBase):
    """A pyserial port whose other end is the simulated arm."""

    def __init__(self, *args, **kwargs):
        self.model: SimulatedArm | None = None
        self._arm: RealtimeArm | None = None
        self.virtual_clock: VirtualClock | None = None  # set for clock=virtual
        self._received = bytearray()  # status bytes that reached the host, not yet read
        self._noise: LineNoise | None = None  # set when the port's rate is not the arm's
        self._wake = threading.Event()
        # its URL's profile file read already (``serial_for_url(url, profile=…)``: armctl's port
        # check read it), used as it was read rather than read a second time
        self._profile = kwargs.pop("profile", None)
        super().__init__(*args, **kwargs)

    # --- opening and closing -------------------------------------------------------------------

    def open(self) -> None:
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        options = parse_sim_url(self.portstr, baud=self._baudrate)
        if self._profile is not None and isinstance(options.profile, str):
            options = dataclasses.replace(options, profile=self._profile)
        try:
            self.model = SimulatedArm(options)
        except Exception as error:  # a bad profile path or a profile that makes no sense
            raise SimOptionError(f"sim:// option profile: {error}") from None
        self._listen_at(self._baudrate)
        self.virtual_clock = VirtualClock() if options.virtual_clock else None
        self._arm = RealtimeArm(self.model, options.time_scale, clock=self.virtual_clock or time.monotonic)
        self._received.clear()
        self._wake.clear()
        self.is_open = True

    def from_url(self, url: str) -> SimOptions:
        return parse_sim_url(url, baud=self._baudrate)

    def close(self) -> None:
        self.is_open = False
        self._wake.set()

    def _reconfigure_port(self) -> None:
        if not isinstance(self._baudrate, numbers.Integral) or not 0 < self._baudrate < 2**32:
            raise ValueError(f"invalid baudrate: {self._baudrate!r}")
        if self.model is not None:  # the port set to another rate once open
            self._listen_at(self._baudrate)

    def _listen_at(self, port_baud: int) -> None:
        """The port set to ``port_baud``: a clean line at the arm's rate, else noise (``LineNoise``)."""
        arm = self.model.options
        self._noise = None if port_baud == arm.baud else LineNoise(port_baud, arm.baud, arm.seed)

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    def _update_break_state(self) -> None:
        pass

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True

    # --- reading -------------------------------------------------------------------------------

    def _check_open(self) -> RealtimeArm:
        if not self.is_open or self._arm is None:
            raise PortNotOpenError()
        return self._arm

    def _collect(self, arm: RealtimeArm) -> None:
        """Move the status bytes that reached the host into the input buffer (lock held)."""
        self._received += self._heard(arm.poll())

    def _heard(self, data: bytes) -> bytes:
        """The arm's bytes as the port reads them: noise at another rate than the arm's."""
        return data if self._noise is None else self._noise.heard(data)

    @property
    def in_waiting(self) -> int:
        arm = self._check_open()
        with arm.lock:
            self._collect(arm)
            return len(self._received)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` status bytes; blocks per ``timeout`` like any pyserial port."""
        arm = self._check_open()
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        self._wake.clear()
        if self.virtual_clock is not None:  # a virtual clock waits for nobody: what is there now
            with arm.lock:
                self._collect(arm)
        while self.is_open and self.virtual_clock is None:
            with arm.lock:
                self._collect(arm)
                if len(self._received) >= size:
                    break
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                break
            pause = arm.wall_seconds_until_output()
            if pause is None or (remaining is not None and pause > remaining):
                pause = remaining
            if self._wake.wait(pause):  # close() or cancel_read()
                break
        with arm.lock:
            data = bytes(self._received[:size])
            del self._received[:size]
        return data

    def next_output_s(self) -> float | None:
        """Model seconds until the next status burst has reached the host (None: never)."""
        return self._check_open().wall_seconds_until_output() if self.virtual_clock else None

    # --- virtual time: the interface armctl/host/virtual_wait.py drives (``clock=virtual`` only) ------

    def next_event_s(self) -> float | None:
        """The clock's reading when the next status burst has fully reached the host (None:
        never); ``next_output_s``'s arithmetic on the clock's own reading."""
        arm = self._check_open()
        with arm.lock:
            return self._next_event_s(arm)

    def _next_event_s(self, arm: RealtimeArm) -> float | None:
        """``next_event_s`` with the lock held."""
        due_s = self.model.next_output_time()
        if due_s is None:
            return None
        return self.virtual_clock.now_s + max(0.0, (due_s - arm.model_now_s()) / arm.time_scale)

    def advance_to(self, t_s: float) -> bytes:
        """Move the clock to ``t_s`` (never back) and read every status byte that has reached the
        host by then: ``read`` after the clock's ``advance_to``, without the wall-clock machinery
        between them (``VirtualWaits`` calls it once per status burst)."""
        arm = self._check_open()
        received = self._received
        with arm.lock:
            self.virtual_clock.advance_to(t_s)
            data = self._heard(self.model.advance(arm.model_now_s()))
            if received:  # bytes left from before (a ``read`` of fewer than arrived)
                data = bytes(received + data)
                received.clear()
        return data

    def virtual_status_run(self, end_s: float | None, min_step_s: float, max_frames: int) -> list:
        """The timing of up to ``max_frames`` bursts (``next_event_s``, at least ``min_step_s``
        on, then ``advance_to``) that would each read one whole status frame and nothing else happens, computed ahead and
        changing nothing (``SimulatedArm.status_run``: [(clock time, kind, due time, …)]; empty
        when the next step is not such a quiet one).  The caller reads them in order — the
        clock at each one's time, its frame from ``status_frame`` — and then commits those it
        read (``commit_status_run``) before anything else touches the port."""
        arm = self._check_open()
        if self._received or self._noise is not None:  # (noise: no status frame to time ahead)
            return []
        with arm.lock:
            return self.model.status_run(self.virtual_clock.now_s, end_s, min_step_s, max_frames,
                                         arm.clock_start_s, arm.time_scale)

    def status_frame(self, kind: int, at_s: float) -> bytes:
        """The status frame of one step of a ``virtual_status_run``."""
        return self.model.status_frame(kind, at_s)

    def status_frames(self, steps: list) -> list[bytes]:
        """The status frames of some steps of a ``virtual_status_run``, in one call."""
        return self.model.status_frames(steps)

    def commit_status_run(self, run: list, frames: int) -> None:
        """The first ``frames`` of ``run`` were read: the model and the clock move to the last one."""
        if frames <= 0:
            return
        with self._check_open().lock:
            self.model.commit_status_run(run, frames)
            self.virtual_clock.advance_to(run[frames - 1][0])

    def cancel_read(self) -> None:
        self._wake.set()

    def reset_input_buffer(self) -> None:
        arm = self._check_open()
        with arm.lock:
            self._collect(arm)
            self._received.clear()

    # --- writing -------------------------------------------------------------------------------

    def write(self, data) -> int:
        """Queue the bytes on the simulated line at the current model time; with a write buffer
        (``write_buffer_bytes``) what does not fit waits until it does — the wall clock sleeps
        (``SerialTimeoutException`` past ``write_timeout``, as pyserial's ports raise), a virtual
        clock moves on — else never blocks."""
        data = to_bytes(data)
        total = len(data)
        arm = self._check_open()
        if self._noise is not None:  # the arm frames nothing sent at another rate
            return total
        deadline = None if self._write_timeout is None else time.monotonic() + self._write_timeout
        while True:
            room = arm.write_room()
            if room is None or room >= len(data):
                arm.write(data)
                return total
            if room:
                arm.write(data[:room])
                data = data[room:]
            wait_s = arm.model_seconds_until_room(len(data))
            if self.virtual_clock is not None:
                self.virtual_clock.advance_to(self.virtual_clock.now_s + max(wait_s, 1e-9))
                continue
            pause = wait_s / arm.time_scale
            if deadline is not None and time.monotonic() + pause > deadline:
                raise SerialTimeoutException("Write timeout")
            if self._wake.wait(pause) and not self.is_open:
                raise PortNotOpenError()

    @property
    def out_waiting(self) -> int:
        return self._check_open().out_waiting()

    def flush(self) -> None:
        """Wait until every byte written has gone over the simulated line."""
        arm = self._check_open()
        if self.virtual_clock is not None:
            self.virtual_clock.advance_to(self.model.host_line_free_s())
            return
        time.sleep(arm.wall_seconds_until_sent())

    def reset_output_buffer(self) -> None:
        """A no-op: bytes handed to the simulated line cannot be taken back (see README)."""
        self._check_open()

    def cancel_write(self) -> None:
        pass

    def send_break(self, duration: float = 0.25) -> None:
        self._check_open()
