"""The probe over a Link: feed it status frames and the link's clock, write what it asks.

Strategy: a thin edge.  The link's reader (a thread, or the virtual clock's waits) hands each
status frame to ``on_status``, which only appends it to a deque; the loop drains the deque
into the pure ``Probe``, asks for the next action, writes or waits.  Ctrl-C, SIGTERM and SIGHUP
only set a flag (``deferred_stop``): the loop, between two actions, switches the probe to
restoring and runs on until the arm is as it was; a second signal leaves at once
(KeyboardInterrupt), and the probe's notes say what is not restored.  After every write and
wait the loop asks the port how many written bytes it still holds (``out_waiting``): the probe
proves its frames' landing times from that, never from ``write()`` returning.
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


def unsent_bytes(port) -> int | None:
    """Bytes written that ``port`` has not sent yet (pyserial's ``out_waiting``), or None when
    the port cannot say (``socket://``, ``rfc2217://``) or fails to."""
    try:
        unsent = port.out_waiting
    except Exception:  # no such property, or an OS error: the link's own reads report a vanished port
        return None
    return unsent if isinstance(unsent, int) and unsent >= 0 else None


def drive(link, probe: Probe, inbox: FrameInbox, progress=None, stop: threading.Event | None = None) -> None:
    """Run ``probe`` on ``link`` to its end.  ``stop`` set (a signal): restore, then end with
    ``probe.interrupted`` true; the caller exits 130.  After each write and each wait the
    probe hears what the port still holds (``Probe.port_report``), when the port can say."""
    stop = stop or threading.Event()
    reports = unsent_bytes(link.port) is not None

    def report() -> None:
        unsent = unsent_bytes(link.port) if reports else None
        if unsent is not None:
            probe.port_report(link.clock(), unsent)

    report()
    while True:
        if stop.is_set() and not probe.interrupted and not probe.done:
            probe.interrupt()
        inbox.drain_into(probe)
        action = probe.next_action(link.clock())
        if action is None:
            return
        if isinstance(action, Write):
            link.write(action.frame)
            report()
            continue
        link.idle(max(action.until_s - link.clock(), MIN_WAIT_S))
        report()
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
