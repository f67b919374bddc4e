"""The simulated arm on a clock: the one place where the simulator meets real time — or,
for ``sim://?clock=virtual``, a clock that moves only when the program using the port waits.

Strategy: the model is pure and takes ``now_s`` as an argument; this wrapper supplies it as
``(clock() − start) × time_scale`` (``time_scale`` 4 = the arm lives four times faster than
the wall clock) and serialises every call with one lock, so a reader thread and a writer thread
can share it.  It never sleeps itself: it says how long the caller may sleep before the next
status byte is due (``wall_seconds_until_output``), and the edges (``protocol_sim``,
``bridge``) do the waiting with whatever primitive suits them.

``VirtualClock`` replaces the wall clock when the waiting itself is simulated: ``Link`` moves
it forward instead of sleeping, so a job runs in milliseconds and the same run gives the same
bytes at the same model times on any machine, however loaded (the end-to-end tests need that).
"""

from __future__ import annotations

import threading
import time
from typing import Callable

from ..clock import VirtualClock  # noqa: F401  (the clock=virtual port's clock; imported from here)
from .model import SimulatedArm


class RealtimeArm:
    def __init__(self, model: SimulatedArm, time_scale: float = 1.0, clock: Callable[[], float] = time.monotonic):
        if not time_scale > 0:
            raise ValueError(f"time scale must be positive, not {time_scale!r}")
        self.model = model
        self.time_scale = float(time_scale)
        self._clock = clock
        self._start_wall_s = clock() - model.now_s / self.time_scale
        self.lock = threading.RLock()

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
        """Run the arm up to now; the status bytes that have reached the host since last time."""
        with self.lock:
            return self.model.advance(self.model_now_s())

    def out_waiting(self) -> int:
        """Host bytes written but not yet fully on the wire."""
        with self.lock:
            return self.model.host_bytes_in_flight(self.model_now_s())

    def wall_seconds_until_output(self) -> float | None:
        """Wall seconds until the next status byte reaches the host (None: never)."""
        with self.lock:
            due_s = self.model.next_output_time()
            if due_s is None:
                return None
            return max(0.0, (due_s - self.model_now_s()) / self.time_scale)

    def wall_seconds_until_sent(self) -> float:
        """Wall seconds until every byte written so far is on the other end of the line."""
        with self.lock:
            return max(0.0, (self.model.host_line_free_s() - self.model_now_s()) / self.time_scale)
