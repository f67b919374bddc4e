"""``armctl jog``'s edge: the one loop where keys, the port, the clock and the screen meet.

Strategy: a thin loop around the pure parts, on the one host driver (armctl/host/driver.py).  Each
wait is on stdin with ``select`` for at most a few tens of milliseconds (less when the session
or the key decoder has a deadline sooner: ``_Terminal``); then the bytes become keys
(``KeyDecoder``), the keys and a snapshot of the arm's state go to the ``JogSession``, and the
effects it returns are carried out in order — frames to the link as the driver's ``Write``s
(and the ``--log``), taught lines to the ``--record`` file — and the panel is refreshed.  Every way out —
quit, Ctrl-C, an error, the port lost, the terminal gone, SIGTERM/SIGHUP — goes through
``session.finish`` (the neutral frame, at once) and then the ``raw_terminal`` and ``Live``
exits that restore the screen.
"""

from __future__ import annotations

import errno
import json
import os
import threading
import time
from dataclasses import dataclass
from datetime import datetime
from typing import Callable

from ..core.actions import Done, Wait, Write
from ..host.driver import Host, drive
from ..errors import ArmctlError, PortError
from ..core.protocol import describe
from .keys import KeyDecoder
from .moves import POSE_KINDS, reported_pose
from ..errors import EXIT_INTERRUPTED, EXIT_PROBLEMS
from .session import JogSession, Record, Send
from .teach import FILE_HEADER, taught_line
from .terminal import TerminalGone, Terminated, raw_terminal, read_input

IDLE_WAIT_S = 0.05  # longest select() wait: how often status is looked at when nothing happens
BUSY_WAIT_S = 0.015  # while a move is in flight or an action waits for status
REFRESH_S = 0.1  # the panel, at most 10 times a second
RENDER_BUDGET_S = 0.03  # no redraw this close to a dead-man deadline (a redraw takes a few ms)


class FrameLog:
    """JSON lines like ``armctl run --log``: every frame written (``tx``) and read (``rx``), and
    every key (``key``), with ``t`` in seconds since the log was opened.  Thread-safe: status
    frames are logged from the link's reader thread."""

    def __init__(self, path: str, clock: Callable[[], float] = time.monotonic) -> None:
        self._file = open(path, "w", encoding="utf-8")
        self._clock = clock
        self._origin = clock()
        self._lock = threading.Lock()

    def _write(self, at_s: float, record: dict) -> None:
        with self._lock:
            if not self._file.closed:
                self._file.write(json.dumps({"t": round(at_s - self._origin, 4), **record}) + "\n")
                self._file.flush()

    def tx(self, command, at_s: float) -> None:
        self._write(at_s, {"dir": "tx", "hex": command.encode().hex(), "frame": describe(command)})

    def rx(self, frame, at_s: float) -> None:
        self._write(at_s, {"dir": "rx", "hex": frame.encode().hex(), "kind": frame.KIND})

    def key(self, name: str, at_s: float) -> None:
        self._write(at_s, {"dir": "key", "key": name})

    def note(self, text: str, at_s: float) -> None:
        self._write(at_s, {"dir": "note", "text": text})

    def close(self) -> None:
        with self._lock:
            self._file.close()


class TeachFile:
    """The ``--record`` file: lines appended, flushed and synced one by one (a crash keeps them).
    Opened at once (so a path that cannot be written fails before the arm moves); a file this
    session created and never wrote to is removed at the end."""

    def __init__(self, path: str) -> None:
        self.path = path
        self._created = not os.path.exists(path)
        self._file = open(path, "a", encoding="utf-8")
        self.lines = 0

    def append(self, line: str) -> None:
        if self._file.tell() == 0:
            self._file.write(FILE_HEADER)
        self._file.write(line)
        self._file.flush()
        os.fsync(self._file.fileno())
        self.lines += 1

    def close(self) -> None:
        self._file.close()
        if self._created and self.lines == 0:
            try:
                os.unlink(self.path)
            except OSError:
                pass


@dataclass
class Outcome:
    exit_code: int
    reason: str
    recorded: int
    unrecorded: int
    stop_failed: str | None = None  # the neutral frame could not be written (the port is gone)


class JogLoop(Host):
    """The jog session on the host driver (armctl/host/driver.py): the engine's side answers the
    session's effects as actions (``next_action``), the host's side waits on the terminal
    (``_Terminal``) and redraws the panel."""

    def __init__(self, link, session: JogSession, decoder: KeyDecoder, *, profile, keymap, url: str,
                 log: FrameLog | None = None, teach: TeachFile | None = None, display=None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.link, self.session, self.decoder = link, session, decoder
        self.profile, self.keymap, self.url = profile, keymap, url
        self.log, self.teach, self.display = log, teach, display
        self.clock = clock
        self._last_refresh = float("-inf")
        self.stop_failed: str | None = None
        self._input = b""  # what the last wait read from the terminal
        self._waited = False  # a wait ended since the keys were last handled
        self._pending: list = []  # the effects of the keys and the tick last handled, carried out in order
        self._round: tuple | None = None  # (now, keys came, state) of that round: its tx records, its redraw

    def run(self, fd: int) -> Outcome:
        session = self.session
        try:
            with raw_terminal(fd):
                try:
                    with self.display or _Nothing():
                        self._refresh(self.clock(), final=True)
                        drive(self, _Terminal(self, fd), self)
                        self._refresh(self.clock(), final=True)
                except BaseException as error:
                    # Any way out that is not a key (a lost port, the terminal gone, SIGTERM,
                    # SIGINT from `kill`, a bug): the neutral frame first, then the terminal.
                    if not session.done:
                        self._stop(*_reason_of(error))
                    raise
        except (KeyboardInterrupt, TerminalGone, Terminated, PortError, OSError):
            pass  # the session has recorded why it ended
        if self.log is not None:
            self.log.note(f"jog ended: {session.reason} (exit {session.exit_code})", self.clock())
        return Outcome(session.exit_code, session.reason, session.recorded, session.unrecorded, self.stop_failed)

    # --- the engine: the session's effects as the driver's actions ------------------------------

    def next_action(self, now: float):
        """Each wait's keys (and the session's tick) handled once, their frames written one by
        one in order (a taught line appended where it comes), then the next wait — or the end."""
        while True:
            if self._pending:
                effect = self._pending.pop(0)
                if isinstance(effect, Send):
                    return Write(effect.command.encode(), effect.command)
                self._record(effect)
                continue
            if self._waited and not self.session.done:
                self._waited = False
                self._handle(now)
                continue
            return Done(self.session.exit_code) if self.session.done else Wait(None)

    def _handle(self, now: float) -> None:
        session = self.session
        state = self.link.snapshot()[0]
        data, self._input = self._input, b""
        keys = self.decoder.feed(data, now) if data else self.decoder.expire(now)
        self._round = (now, bool(keys), state)
        for key in keys:
            if self.log is not None:
                self.log.key(key.name, now)
            self._pending += session.key(key.name, now, state)
            if session.done:
                return
        self._pending += session.tick(now, state)

    # --- the host: the driver's hooks ----------------------------------------------------------

    def wrote(self, action: Write, now: float) -> None:
        if self.log is not None:
            self.log.tx(action.statement, self._round[0] if self._round else now)

    def waiting(self, action: Wait, now: float) -> float:
        """The panel of the round just handled, then a wait on the terminal until the session's,
        the key decoder's or the panel's next deadline (at most ``IDLE_WAIT_S``)."""
        if self._round is not None:
            round_s, keys, state = self._round
            self._round = None
            self._refresh(round_s, force=keys, state=state)
        now_s = self.clock()
        return now_s + self._timeout(now_s)

    def waited(self) -> None:
        self._waited = True

    def _timeout(self, now: float) -> float:
        wait = BUSY_WAIT_S if self.session.waiting else IDLE_WAIT_S
        for deadline in (self.session.next_deadline(), self.decoder.deadline(), self._last_refresh + REFRESH_S):
            if deadline is not None:
                wait = min(wait, deadline - now)
        return max(wait, 0.0)

    def _carry_out(self, effects: list, now: float) -> None:
        """Effects carried out at once, outside the driver (the neutral frame on the way out)."""
        for effect in effects:
            if isinstance(effect, Send):
                self.link.write(effect.command.encode())
                if self.log is not None:
                    self.log.tx(effect.command, now)
            else:
                self._record(effect)

    def _record(self, effect) -> None:
        if isinstance(effect, Record) and self.teach is not None:
            self.teach.append(taught_line(effect.mode, effect.pose, effect.speed, datetime.now().astimezone()))

    def _stop(self, reason: str, code: int) -> None:
        """Neutral at once, on the way out; a port that fails again is left alone."""
        try:
            self._carry_out(self.session.finish(self.clock(), reason, code), self.clock())
        except (ArmctlError, OSError) as error:
            self.stop_failed = str(error)

    def _refresh(self, now: float, force: bool = False, state=None, final: bool = False) -> None:
        """Redraw at most every REFRESH_S (or RENDER_BUDGET_S after a key), never just before a
        dead-man deadline; ``final`` draws regardless (first and last panel)."""
        if self.display is None:
            return
        if not final:
            if now - self._last_refresh < (RENDER_BUDGET_S if force else REFRESH_S):
                return
            deadline = self.session.next_deadline()
            if deadline is not None and deadline - now < RENDER_BUDGET_S:
                return
        from .view import render_jog

        state = state if state is not None else self.link.snapshot()[0]
        pose = reported_pose(state, self.profile.kinematics)
        view = self.session.view(self.url, self.teach.path if self.teach else None)
        gripper = (self.profile.pwm.gripper_open_us, self.profile.pwm.gripper_close_us)
        self.display.update(render_jog(view, pose, state.pwm_us, self.keymap, gripper), refresh=True)
        self._last_refresh = now


class _Terminal:
    """The driver's link for jog: the port's writes and error, the jog's clock, and a wait that
    is a wait for keys (``read_input``: until the time given, or the first key)."""

    def __init__(self, loop: JogLoop, fd: int) -> None:
        self.loop, self.fd, self.clock = loop, fd, loop.clock

    @property
    def error(self):
        return self.loop.link.error

    def write(self, frame: bytes) -> None:
        self.loop.link.write(frame)

    def wait(self, until_s: float, news=None) -> None:
        self.loop._input = read_input(self.fd, until_s - self.clock())


class _Nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def _reason_of(error: BaseException) -> tuple[str, int]:
    if isinstance(error, KeyboardInterrupt):
        return "interrupted", EXIT_INTERRUPTED
    if isinstance(error, OSError) and not isinstance(error, ArmctlError):
        if error.errno == errno.EIO:  # writing the panel to a terminal that hung up
            return "the terminal went away", EXIT_PROBLEMS
        return (error.strerror or str(error)), EXIT_PROBLEMS
    return (str(error) or type(error).__name__), EXIT_PROBLEMS


def wait_for_pose(link, timeout_s: float) -> str | None:
    """None once the arm has reported every pose kind; else why we give up (after ``timeout_s``)."""
    if link.wait_until(lambda s: all(k in s.last_seen for k in POSE_KINDS), timeout_s):
        return None
    _, received, skipped, frames = link.snapshot()
    if received == 0:
        heard = "received nothing (is the arm powered and the cable on the host connector?)"
    elif frames == 0:
        heard = f"received {received} bytes but no status frame (is the baud rate right?)"
    else:
        heard = f"{frames} status frames, but not the position, joints and PWM"
    return f"no status from {link.url} within {timeout_s:g} s: {heard}; refusing to jog"
