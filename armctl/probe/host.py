"""The probe over a Link: feed it status frames and the link's clock, write what it asks.

Strategy: a thin edge.  The link's reader (a thread, or the virtual clock's waits) hands each
status frame to ``on_status``, which only appends it to a deque; the one host driver
(armctl/host/driver.py) runs the pure ``Probe`` — asks for the next action, writes or waits — and
``ProbeHost`` drains the deque into it before each action.  Ctrl-C, SIGTERM and SIGHUP
only set a flag (``deferred_stop``): the loop, between two actions, switches the probe to
restoring and runs on until the arm is as it was; a second signal leaves at once
(KeyboardInterrupt), and the probe's notes say what is not restored.  After every write and
wait the loop asks the port how many written bytes it still holds (``out_waiting``): the probe
proves its frames' landing times from that, never from ``write()`` returning.
"""

from __future__ import annotations

import threading
from collections import deque

from ..core.actions import Wait, Write
from ..host.driver import Host, drive as run
from .plan import Probe

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


class ProbeHost(Host):
    """The probe's hooks of the host driver: the stop and the frames read meanwhile before each
    action, the port's report of what it still holds after each write and wait, and the
    progress after a wait."""

    def __init__(self, link, probe: Probe, inbox: FrameInbox, progress, stop: threading.Event) -> None:
        self.link, self.probe, self.inbox, self.progress, self.stop = link, probe, inbox, progress, stop
        self.reports = unsent_bytes(link.port) is not None

    def report(self) -> None:
        unsent = unsent_bytes(self.link.port) if self.reports else None
        if unsent is not None:
            self.probe.port_report(self.link.clock(), unsent)

    def turn(self) -> None:
        probe = self.probe
        if self.stop.is_set() and not probe.interrupted and not probe.done:
            probe.interrupt()
        self.inbox.drain_into(probe)

    def wrote(self, action: Write, now: float) -> None:
        self.report()

    def waiting(self, action: Wait, now: float) -> float:
        now_s = self.link.clock()
        return now_s + max(action.until_s - now_s, MIN_WAIT_S)

    def waited(self) -> None:
        self.report()
        if self.link.error is not None:
            raise self.link.error
        if self.progress is not None:
            self.progress(self.probe)


def drive(link, probe: Probe, inbox: FrameInbox, progress=None, stop: threading.Event | None = None) -> None:
    """Run ``probe`` on ``link`` to its end (the host driver, armctl/host/driver.py).  ``stop`` set
    (a signal): restore, then end with ``probe.interrupted`` true; the caller exits 130.  After
    each write and each wait the probe hears what the port still holds (``Probe.port_report``),
    when the port can say."""
    host = ProbeHost(link, probe, inbox, progress, stop or threading.Event())
    host.report()
    run(probe, link, host)


def deferred_stop(stop: threading.Event):
    """Ctrl-C, SIGTERM, SIGHUP set ``stop`` (the probe restores the arm, then exits 130); a
    second one raises KeyboardInterrupt at once."""
    from ..host.stop_signals import stop_signals

    def on_stop(_signum: int) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    return stop_signals(on_stop)
