"""The probe's engine: steps as generators, driven by status frames and ``now``; pure.

Strategy (sans-I/O, like armctl/jog/session.py): each measurement is a generator that yields
what it needs — ``Send(command)`` (a frame to write) or ``Wait(until_s, ready)`` (feed me status
frames until ``ready()`` holds or the time comes) — and returns a ``Finding``.  ``Probe`` runs
the steps in order and turns their wishes into ``Write``/``Wait`` actions for a host: it paces
writes to the line rate (one frame ahead of the wire, so the line model says when each lands;
further ahead only where ``WireLog`` — the port's own reports of what it still holds, fed by the
host — proves the landing) and hands each step the landing time the model expects.  ``Seen``
keeps every status frame with its time.  ``interrupt()`` abandons the running step for the
restore step, which is also the last step of a normal run: one mechanism puts back what the
probe changed.

No clock, no port, no threads: a host (armctl/probe/host.py) feeds frames and time; the tests
feed a simulator in virtual time.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from itertools import takewhile
from typing import Iterator

from ..core.actions import Wait, Write  # a step's wish Wait(until_s, ready), and the host's actions (the probe's Command as Write.statement)
from ..core.line import STATUS_SIZE
from ..core.protocol import Command, PauseStatus, StatusFrame, byte_seconds, frame_seconds
from ..core.evidence import AGREEING_REPORTS, agreeing_runs
from .landing import WireLog

SURE, LIKELY, UNSURE, NOT_MEASURED = "sure", "likely", "unsure", "not measured"
# Readings from the arm are trusted once two frames of a kind in a row agree: one status byte
# flipped on the line (H9: no checksum) cannot then make the probe claim a value (armctl/core/evidence.py).
AGREEING_FRAMES = AGREEING_REPORTS
# A port that holds written bytes and sends none for this long is stuck (at 9600 a byte leaves
# every 1.04 ms while it works): the probe stops rather than wait for ever.
LINE_STUCK_S = 10.0


class ProbeStop(Exception):
    """A fact that makes the rest of the probe meaningless (a wrong encoding, no status): the
    probe restores what it changed and stops with this message (exit 1)."""


@dataclass(frozen=True)
class Finding:
    """One measured setting (or fact): what the document says, what the arm showed, why, how sure."""

    name: str
    default: object
    value: object  # None when not measured (or too unsure to state)
    evidence: str
    confidence: str = SURE
    details: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Send:
    """A step's wish: write this frame (the step receives the landing time the line model
    expects; ``Probe.landed_by`` proves it from the port's reports).  ``ahead_s``: the frame may
    go this much more line time ahead of the wire — only on a port that reports what it still
    holds, where the landing is proven, not assumed; the port's buffer then keeps the line busy
    between two of the host's wake-ups."""

    command: Command
    raw: bytes | None = None  # the bytes, when they are not ``command.encode()`` (a byte-order test)
    ahead_s: float = 0.0


class Seen:
    """Every status frame read, with the time its last byte arrived (less its transit, so the
    time the arm built it)."""

    def __init__(self, transit_s: float) -> None:
        self.transit_s = transit_s
        self.frames: list[tuple[float, StatusFrame]] = []
        self.by_kind: dict[int, list[tuple[float, StatusFrame]]] = defaultdict(list)

    def feed(self, frame: StatusFrame, now_s: float) -> None:
        entry = (now_s - self.transit_s, frame)
        self.frames.append(entry)
        self.by_kind[frame.KIND].append(entry)

    def since(self, kind: int, since_s: float) -> list[tuple[float, StatusFrame]]:
        entries = self.by_kind.get(kind, [])
        low, high = 0, len(entries)
        while low < high:  # the first entry built at or after since_s
            middle = (low + high) // 2
            if entries[middle][0] < since_s:
                low = middle + 1
            else:
                high = middle
        return entries[low:]

    def agreed_runs(self, kind: int, since_s: float, key=lambda f: f) -> list[tuple[float, object]]:
        """(start time, value) of every run of ``AGREEING_FRAMES``+ equal readings since ``since_s``
        (armctl/core/evidence.py ``agreeing_runs``)."""
        readings = ((t, key(frame)) for t, frame in self.since(kind, since_s))
        return [(start_s, value) for start_s, _, value in agreeing_runs(readings)]

    def agreed(self, kind: int, since_s: float = float("-inf"), key=lambda f: f,
               until_s: float = float("inf")) -> tuple[float, object] | None:
        """The latest value (``key(frame)``) that ``AGREEING_FRAMES`` consecutive frames of
        ``kind`` built from ``since_s`` to ``until_s`` report, with the time its run began; or None."""
        readings = ((t, key(frame)) for t, frame in takewhile(lambda entry: entry[0] <= until_s,
                                                             self.since(kind, since_s)))
        runs = agreeing_runs(readings)
        return (runs[-1][0], runs[-1][2]) if runs else None


def pwm_of(frame: PauseStatus) -> int:
    return frame.pwm_us


def paused_of(frame: PauseStatus) -> bool:
    return frame.paused


def xyz_of(frame) -> tuple[float, float, float]:
    return (frame.x_mm, frame.y_mm, frame.z_mm)


class Probe:
    """Runs ``steps`` (callables taking the probe, returning a step generator) then ``restore``."""

    def __init__(self, steps, restore, baud: int, start_s: float, after_sent_bytes: int = 0) -> None:
        self.baud = baud
        self.frame_s = frame_seconds(baud)
        self.wire = WireLog(byte_seconds(baud), after_sent_bytes)  # what the port says has left it
        self.seen = Seen(STATUS_SIZE * byte_seconds(baud))
        self.start_s = self.now_s = start_s
        self.line_free_s = start_s  # when the last frame written has fully landed
        self.findings: list[Finding] = []
        self.notes: list[str] = []  # what the probe did that a user should know (restored …)
        self.sent: list[tuple[float, Command]] = []  # landing time, command
        self.stopped: ProbeStop | None = None
        self.interrupted = False
        self.done = False
        self.current = ""  # the step running, for a progress display
        self._steps = list(steps)
        self._restore = restore
        self._restoring = False
        self._generator: Iterator | None = None
        self._pending: Send | Wait | None = None
        self._reply: float | None = None

    # --- what a host calls --------------------------------------------------------------------

    def feed(self, frame: StatusFrame, now_s: float) -> None:
        self.now_s = max(self.now_s, now_s)
        self.seen.feed(frame, now_s)

    def port_report(self, now_s: float, unsent_bytes: int) -> None:
        """The port still holds ``unsent_bytes`` of what was written (pyserial's ``out_waiting``):
        the line stays busy at least that long, whatever the model expected."""
        self.now_s = max(self.now_s, now_s)
        self.wire.report(now_s, unsent_bytes)
        self.line_free_s = max(self.line_free_s, now_s + unsent_bytes * self.wire.byte_s)

    def interrupt(self) -> None:
        """Ctrl-C: abandon the running step; restore what was changed, then stop."""
        if not self._restoring:
            self.interrupted = True
            self._start_restore()

    def next_action(self, now_s: float) -> Write | Wait | None:
        """What to do now: write a frame, wait (feeding frames) or nothing more (None)."""
        self.now_s = max(self.now_s, now_s)
        while not self.done:
            pending = self._pending
            if pending is None:
                pending = self._pending = self._advance()
                if pending is None:
                    continue
            if isinstance(pending, Wait):
                if (pending.ready is not None and pending.ready()) or self.now_s >= pending.until_s:
                    self._pending, self._reply = None, self.now_s
                    continue
                return pending
            # Send: at most one frame ahead of the wire, so the line model knows when it lands —
            # or up to ``ahead_s`` more where the port's reports prove the landing instead
            ahead_s = self.frame_s * 1.001 + (pending.ahead_s if self.wire.reporting else 0.0)
            if self.line_free_s - self.now_s > ahead_s:
                if self.wire.stuck_s(self.now_s) > LINE_STUCK_S:
                    self._line_stuck()
                    continue
                return Wait(self.line_free_s - ahead_s)
            self.line_free_s = max(self.now_s, self.line_free_s) + self.frame_s
            self.sent.append((self.line_free_s, pending.command))
            raw = pending.raw or pending.command.encode()
            self.wire.wrote(len(raw))
            self._pending, self._reply = None, self.line_free_s
            return Write(raw, pending.command)
        return None

    def landed_by(self, end: int, expected_s: float) -> float | None:
        """The frame ending at stream position ``end`` (``wire.written_bytes`` after its Send)
        has landed by this time: not before the port's reports show it gone (None: they do not
        yet), nor before ``expected_s``, the line model's time — a buffer the port does not count
        (a bridge that reads the bytes at once and puts them on its own line) passes them on no
        faster than the line.  A port that cannot report: the line model's time alone."""
        if not self.wire.reporting:
            return expected_s
        reported_s = self.wire.landed_by(end)
        return None if reported_s is None else max(reported_s, expected_s)

    def earliest_landing(self, end: int, written_s: float) -> float:
        """The frame ending at ``end``, handed to the port at ``written_s``, cannot have landed
        before this: its own wire time after the write, and not while the port still held it."""
        return max(written_s + self.frame_s, self.wire.not_landed_at(end))

    @property
    def arm_time_s(self) -> float:
        return self.now_s - self.start_s

    # --- running the steps --------------------------------------------------------------------

    def _advance(self) -> Send | Wait | None:
        if self._generator is None:
            if self._steps:
                name, make = self._steps.pop(0)
                self.current = name
                made = make(self)
                if not hasattr(made, "send"):  # a step that needs no frames: its result at once
                    self._record(made)
                    return None
                self._generator, self._reply = made, None
            elif not self._restoring:
                self._start_restore()
            else:
                self.done = True
                return None
        try:
            if self._reply is None:
                return next(self._generator)
            reply, self._reply = self._reply, None
            return self._generator.send(reply)
        except StopIteration as end:
            self._generator = None
            self._record(end.value)
            return None
        except ProbeStop as stop:
            if self._restoring:  # restoring failed: say so, nothing more to try
                self.notes.append(f"not restored: {stop}")
                self.done = True
                return None
            self.stopped = stop
            self._start_restore()
            return None

    def _line_stuck(self) -> None:
        """The port holds bytes and has sent none for ``LINE_STUCK_S``: nothing reaches the arm.
        Stop (restoring needs the line too: if it is stuck while restoring, say so and end)."""
        stop = ProbeStop(f"the port has sent nothing for {self.wire.stuck_s(self.now_s):.1f} s with "
                         f"{self.wire.unsent_bytes()} bytes waiting: nothing reaches the arm (hardware flow "
                         "control? the adapter or the cable?)")
        self._pending = None
        if self._restoring:
            self.notes.append(f"not restored: {stop}")
            self.done = True
            return
        self.stopped = stop
        self._start_restore()

    def _record(self, result) -> None:
        if isinstance(result, Finding):
            self.findings.append(result)
        elif result:
            self.findings.extend(result)

    def _start_restore(self) -> None:
        self._steps.clear()
        self._restoring = True
        self._pending, self._reply = None, None
        self.current = "restoring"
        self._generator = self._restore(self)

    def finding(self, name: str) -> Finding | None:
        for found in self.findings:
            if found.name == name:
                return found
        return None
