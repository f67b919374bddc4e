"""Continuous jog as a dead-man switch: which joystick frames to send, and when.

Strategy: pure, time passed in.  The arm keeps moving an axis while the last joystick value it
received for that axis is off-centre (PROTOCOL.md, control 30/7 — an assumption), and a
terminal never reports a key release: it only stops sending auto-repeats, and those begin
after an initial delay.  So motion is a lease that every key event renews and that expires on
its own:

- the first press of a jog key starts the axis (one frame) and leases it until
  ``press + initial_delay_s`` — a tap moves no longer than the initial repeat delay;
- the same key again (an auto-repeat, or a second tap) renews the lease to
  ``last key + repeat_gap_s`` (the default 100 ms keeps the neutral within 150 ms of the last
  repeat at 30 repeats/s, with two repeats allowed to go missing);
- both leases end ``wake_margin_s`` (20 ms) early, so the edge's wake-up latency does not make a
  tap move longer than the delay;
- when the lease expires, or on ``stop`` (space, a mode change, quit, Ctrl-C, an error, the
  terminal gone — the caller decides), the neutral value goes out at once.

A frame is written only when the value changes (never a stream of repeats), so the
connector's FIFO stays empty and a neutral acts the moment it lands.  Non-neutral frames are
paced to the line: one is written only when the previous frame has left the wire, and a value
superseded before that is never sent; neutral frames are never held back.  So at most two
frames are ever on their way.  ``refresh_s`` (off by default) would resend an unchanged value
that often, for an arm that wants to hear from the host; the simulator does not need it.

A keyboard whose auto-repeat delay is not shorter than ``initial_delay_s`` sends its first
repeat after the tap lease has ended: the axis stops and starts again (a stutter of about one
frame time).  That is the price of the tap rule; set the delay a little above the keyboard's.

``poll(now)`` returns what is due; ``next_deadline()`` says when to call it again.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.protocol import JOYSTICK_LINEAR_AXIS, JOYSTICK_NEUTRAL, Joystick

NEVER = float("-inf")


@dataclass(frozen=True)
class DeadmanTiming:
    initial_delay_s: float = 0.5  # a tap moves no longer than this
    repeat_gap_s: float = 0.1  # once repeats flow: neutral this long after the last one
    line_s: float = 0.05  # one 48-byte frame on the wire (wall seconds)
    refresh_s: float | None = None  # resend an unchanged non-neutral value this often (None: never)
    wake_margin_s: float = 0.020  # leases end this much early: the edge's wake-up latency


def neutral(axis: int) -> Joystick:
    """The stand-still frame for a joystick axis."""
    count = 3 if axis == JOYSTICK_LINEAR_AXIS else 1
    return Joystick(axis, (JOYSTICK_NEUTRAL,) * count)


class Deadman:
    """The continuous-jog state machine.  Every method returns the frames to write now."""

    def __init__(self, timing: DeadmanTiming = DeadmanTiming()) -> None:
        self.timing = timing
        self.wanted: Joystick | None = None  # the motion the keys ask for
        self.sent: dict[int, Joystick] = {}  # axis → the non-neutral value the arm last got
        self.first_key_s = NEVER
        self.last_key_s = NEVER
        self.repeats = 0
        self.line_free_s = NEVER  # when the last frame written has left the wire
        self.last_write_s = NEVER
        self.still_after_s = NEVER  # the last neutral has reached the arm by then

    # --- state ------------------------------------------------------------------------------

    @property
    def moving(self) -> bool:
        """True while the arm may be moving: a non-neutral value was sent and not yet undone."""
        return bool(self.sent)

    @property
    def active(self) -> bool:
        return self.wanted is not None or bool(self.sent)

    def lease_end(self) -> float | None:
        """When the wanted motion expires (None: nothing is wanted)."""
        if self.wanted is None:
            return None
        if self.repeats == 0:
            return self.first_key_s + self.timing.initial_delay_s - self.timing.wake_margin_s
        return self.last_key_s + self.timing.repeat_gap_s - self.timing.wake_margin_s

    def next_deadline(self) -> float | None:
        """The next time ``poll`` has something to do."""
        if self.wanted is None:
            return None
        times = [self.lease_end()]
        if self.sent.get(self.wanted.axis) != self.wanted:
            times.append(self.line_free_s)
        elif self.timing.refresh_s:
            times.append(self.last_write_s + self.timing.refresh_s)
        return min(times)

    # --- events -----------------------------------------------------------------------------

    def press(self, command: Joystick, now: float) -> list[Joystick]:
        """A jog key arrived asking for ``command`` (axis and non-neutral values)."""
        if command == self.wanted:
            self.last_key_s = now
            self.repeats += 1
            return self.poll(now)
        out = [self._write(neutral(axis), now) for axis in list(self.sent) if axis != command.axis]
        self.wanted = command
        self.first_key_s = self.last_key_s = now
        self.repeats = 0
        return out + self.poll(now)

    def stop(self, now: float) -> list[Joystick]:
        """Neutral at once on every axis that may be moving; forget the wanted motion."""
        self.wanted = None
        return [self._write(neutral(axis), now) for axis in list(self.sent)]

    def poll(self, now: float) -> list[Joystick]:
        """Whatever is due at ``now``: the lease's end, a paced value, a refresh."""
        wanted = self.wanted
        if wanted is None:
            return []
        if now >= self.lease_end():
            return self.stop(now)
        if self.sent.get(wanted.axis) != wanted:
            if now >= self.line_free_s:
                return [self._write(wanted, now)]
        elif self.timing.refresh_s and now >= self.last_write_s + self.timing.refresh_s and now >= self.line_free_s:
            return [self._write(wanted, now)]
        return []

    def _write(self, command: Joystick, now: float) -> Joystick:
        start = max(now, self.line_free_s)
        self.line_free_s = start + self.timing.line_s
        self.last_write_s = now
        if command.is_still:
            self.sent.pop(command.axis, None)
            self.still_after_s = self.line_free_s
        else:
            self.sent[command.axis] = command
        return command
