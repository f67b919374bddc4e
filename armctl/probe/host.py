"""The probe over a Link: feed it status frames and the link's clock, write what it asks.

Strategy: a thin edge.  The link's reader (a thread, or the virtual clock's waits) hands each
status frame to ``on_status``, which only appends it to a deque; the loop drains the deque
into the pure ``Probe``, asks for the next action, writes or waits.  Ctrl-C, SIGTERM and SIGHUP
only set a flag (``deferred_stop``): the loop, between two actions, switches the probe to
restoring and runs on until the arm is as it was; a second signal leaves at once
(KeyboardInterrupt), and the probe's notes say what is not restored.
"""

from __future__ import annotations

import threading
from collections import deque

from .plan import Probe, Write

MIN_WAIT_S = 0.001


class FrameInbox:
    """Status frames from the link's reader, for the loop (``on_status`` runs in the reader thread)."""

    def __init__(self) -> None:
        self._frames: deque = deque()
        self._lock = threading.Lock()

    def __call__(self, frame, now_s: float) -> None:
        with self._lock:
            self._frames.append((frame, now_s))

    def drain_into(self, probe: Probe) -> None:
        with self._lock:
            frames, self._frames = self._frames, deque()
        for frame, now_s in frames:
            probe.feed(frame, now_s)


def drive(link, probe: Probe, inbox: FrameInbox, progress=None, stop: threading.Event | None = None) -> None:
    """Run ``probe`` on ``link`` to its end.  ``stop`` set (a signal): restore, then end with
    ``probe.interrupted`` true; the caller exits 130."""
    stop = stop or threading.Event()
    while True:
        if stop.is_set() and not probe.interrupted and not probe.done:
            probe.interrupt()
        inbox.drain_into(probe)
        action = probe.next_action(link.clock())
        if action is None:
            return
        if isinstance(action, Write):
            link.write(action.frame)
            continue
        link.idle(max(action.until_s - link.clock(), MIN_WAIT_S))
        if link.error is not None:
            raise link.error
        if progress is not None:
            progress(probe)


def deferred_stop(stop: threading.Event):
    """Ctrl-C, SIGTERM, SIGHUP set ``stop`` (the probe restores the arm, then exits 130); a
    second one raises KeyboardInterrupt at once."""
    from ..stop_signals import stop_signals

    def on_stop(_signum: int) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    return stop_signals(on_stop)
