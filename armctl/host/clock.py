"""The one clock of an opened port: model seconds, on the wall or virtual.

Strategy: every time armctl reasons about — status frames stamped as read, the streamer's
decisions, the job engine's deadlines — is *model* time: the arm's own seconds.  For a real arm
that is the wall clock; for ``sim://?speed=N`` it is the wall clock × N (the simulated arm lives
N times faster); for ``sim://?clock=virtual`` it is a ``VirtualClock`` that moves only when the
program using the port waits, so waiting costs nothing and a host jumps from event to event.
The port owns the clock (``Link.clock``, made once when it opens, from the port itself and the
``sim://`` options parsed once by armctl/sim/protocol_sim.py: armctl/host/link.py's ``port_clock``); everything else asks it
(``now()``, ``virtual``, ``wall_seconds``) and waits through the link (``Link.wait``), so no
module branches on the kind of port.
"""

from __future__ import annotations

import time
from typing import Callable


class Clock:
    """Model seconds: ``source()`` (wall seconds) × ``scale``."""

    virtual = False

    def __init__(self, scale: float = 1.0, source: Callable[[], float] = time.monotonic) -> None:
        if not scale > 0:
            raise ValueError(f"a clock's scale must be positive, not {scale!r}")
        self.scale = float(scale)
        self._source = source

    def now(self) -> float:
        return self._source() * self.scale

    def __call__(self) -> float:  # a Clock is also the plain callable older callers expect
        return self.now()

    def wall_seconds(self, model_s: float) -> float:
        """How long ``model_s`` of model time takes on the wall (0 for a virtual clock)."""
        return model_s / self.scale


class VirtualClock(Clock):
    """Model seconds that pass only when ``advance_to`` is called; never goes back."""

    virtual = True

    def __init__(self, start_s: float = 0.0) -> None:
        self.scale = 1.0
        self.now_s = float(start_s)

    def now(self) -> float:
        return self.now_s

    def __call__(self) -> float:
        return self.now_s

    def wall_seconds(self, model_s: float) -> float:
        return 0.0

    def advance_to(self, t_s: float) -> None:
        if t_s > self.now_s:
            self.now_s = float(t_s)


def as_clock(clock) -> Clock:
    """A ``Clock`` from a Clock or a plain callable of model seconds (tests pass lambdas)."""
    return clock if isinstance(clock, Clock) else Clock(1.0, clock)

