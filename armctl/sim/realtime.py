"""The simulated arm on a clock: the one place where the simulator meets real time — or,
for ``sim://?clock=virtual``, a clock that moves only when the program using the port waits.

Strategy: the model is pure and takes ``now_s`` as an argument; this wrapper supplies it as
``(clock() − start) × time_scale`` (``time_scale`` 4 = the arm lives four times faster than
the wall clock) and serialises every call with one lock, so a reader thread and a writer thread
can share it.  It never sleeps itself: it says how long the caller may sleep before the next
status byte is due (``wall_seconds_until_output``), and the edges (``protocol_sim``,
``bridge``) do the waiting with whatever primitive suits them.

The line's edges a real port has are options of the arm (``SimOptions``) and live here, where
real time is: ``read_granularity_s`` holds status bytes back to the next tick (a USB adapter's
latency timer), ``write_buffer_bytes`` bounds what the host may hand over ahead of the wire
(``write_room``; the edges block a writer while it is full, as a tty does).

``VirtualClock`` replaces the wall clock when the waiting itself is simulated: ``Link`` moves
it forward instead of sleeping, so a job runs in milliseconds and the same run gives the same
bytes at the same model times on any machine, however loaded (the end-to-end tests need that).
"""

from __future__ import annotations

import math
import threading
import time
from typing import Callable

from ..host.clock import VirtualClock  # noqa: F401  (the clock=virtual port's clock; imported from here)
from .model import SimulatedArm
from .wire import TIME_EPSILON_S


class RealtimeArm:
    def __init__(self, model: SimulatedArm, time_scale: float = 1.0, clock: Callable[[], float] = time.monotonic):
        if not time_scale > 0:
            raise ValueError(f"time scale must be positive, not {time_scale!r}")
        self.model = model
        self.time_scale = float(time_scale)
        self._clock = clock
        self._start_wall_s = clock() - model.now_s / self.time_scale
        self.lock = threading.RLock()
        # The line's edges (``SimOptions``): status bytes held until the next read tick, and the
        # host's write buffer
        self.read_granularity_s = model.options.read_granularity_s
        self.write_buffer_bytes = model.options.write_buffer_bytes
        self._held = bytearray()
        self._release_s: float | None = None  # the tick the held bytes reach the host at

    @property
    def clock_start_s(self) -> float:
        """The clock's reading at model time 0 (model time = (clock − this) × ``time_scale``)."""
        return self._start_wall_s

    def model_now_s(self) -> float:
        return (self._clock() - self._start_wall_s) * self.time_scale

    def write(self, data: bytes) -> None:
        """Hand bytes to the simulated line now; returns at once (they queue on the wire)."""
        with self.lock:
            self.model.write(data, self.model_now_s())

    def poll(self) -> bytes:
        """Run the arm up to now; the status bytes that have reached the host since last time —
        with a read granularity, at the first tick (a multiple of it, model time) at or after
        they landed, all those held until then at once."""
        with self.lock:
            now_s = self.model_now_s()
            data = self.model.advance(now_s)
            tick_s = self.read_granularity_s
            if not tick_s:
                return data
            if data:
                self._held += data
                if self._release_s is None:
                    self._release_s = math.ceil(now_s / tick_s - TIME_EPSILON_S) * tick_s
            if self._release_s is None or now_s < self._release_s - TIME_EPSILON_S:
                return b""
            data, self._held, self._release_s = bytes(self._held), bytearray(), None
            return data

    def write_room(self) -> int | None:
        """Bytes the host's write buffer takes now (None: no limit)."""
        limit = self.write_buffer_bytes
        if limit is None:
            return None
        with self.lock:
            return max(0, limit - self.model.host_bytes_in_flight(self.model_now_s()))

    def model_seconds_until_room(self, want_bytes: int) -> float:
        """Model seconds until the write buffer takes ``want_bytes`` (at most its size) more."""
        with self.lock:
            limit = self.write_buffer_bytes
            return max(0.0, self.model.host_room_at_s(limit, min(want_bytes, limit)) - self.model_now_s())

    def out_waiting(self) -> int:
        """Host bytes written but not yet fully on the wire."""
        with self.lock:
            return self.model.host_bytes_in_flight(self.model_now_s())

    def wall_seconds_until_output(self) -> float | None:
        """Wall seconds until the next status byte reaches the host (None: never)."""
        with self.lock:
            due_s = self.model.next_output_time()
            tick_s = self.read_granularity_s
            if self._release_s is not None:
                due_s = self._release_s  # (what lands before the tick goes with it)
            elif due_s is not None and tick_s:
                due_s = math.ceil(due_s / tick_s - TIME_EPSILON_S) * tick_s
            if due_s is None:
                return None
            return max(0.0, (due_s - self.model_now_s()) / self.time_scale)

    def wall_seconds_until_sent(self) -> float:
        """Wall seconds until every byte written so far is on the other end of the line."""
        with self.lock:
            return max(0.0, (self.model.host_line_free_s() - self.model_now_s()) / self.time_scale)
