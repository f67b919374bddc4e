"""Feed override: the speed of frames not yet sent, rescaled by a percentage.

Strategy: a pure function of a command and a percentage, applied at the last moment — to the
frame the host is about to write — so a change acts on the next frame written, and the
streamer plans the scaled frame (it is what ``wrote`` is given): its effect shows within the
lead.  Every speed slot a frame carries is scaled by the same factor (F of G1, G6, G300/G301;
F and Q of G220/G222/G230); acceleration (K), delays and control frames are left alone: an
override changes how fast the arm goes, not how hard it accelerates or how long it waits.

Never past the profile: a scaled speed is clamped to L201's own limit
(``speed_limits.speed_limit``, which lint's rule calls too: one fact in one place), rounded down to what a 32-bit float can
carry, so every scaled frame passes the lint speed rule; the result says when it clamped.
100 % returns the very command given (byte for byte).  The two frames of an arc take one
percentage: ``FeedOverride`` latches the G300's for its G301, so an arc is never half one
speed and half another.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, replace

from .protocol import AccelLinearMove, ArcEnd, ArcStart, FLOAT_CODEC, Command, JointMove, LinearMove, as_f32
from .speed_limits import speed_limit

FEED_MIN_PERCENT, FEED_MAX_PERCENT, FEED_STEP_PERCENT = 10, 200, 10
SPEED_FIELDS = {
    LinearMove: ("speed_mm_min",),
    AccelLinearMove: ("speed0_mm_min", "speed1_mm_min"),
    JointMove: ("speed_deg_s",),
    ArcStart: ("speed_mm_min",),
    ArcEnd: ("speed_mm_min",),
}
_BITS = struct.Struct("<I")
_SMALLEST_F32 = 1.401298464324817e-45  # a positive speed never scales to 0 (the frame would be refused)


def clamp_percent(percent: int) -> int:
    """``percent`` on the 10 % grid, within 10…200 %."""
    stepped = int(round(percent / FEED_STEP_PERCENT)) * FEED_STEP_PERCENT
    return max(FEED_MIN_PERCENT, min(FEED_MAX_PERCENT, stepped))


def _f32_at_most(limit: float) -> float:
    """The largest 32-bit float not above ``limit`` (a positive profile limit): what a
    clamped slot carries, so the frame passes L201, which judges the value sent."""
    value = as_f32(limit)
    if value is None or value > limit:
        bits = _BITS.unpack(FLOAT_CODEC.pack(value if value is not None else 3.4028234663852886e38))[0]
        value = FLOAT_CODEC.unpack(_BITS.pack(bits - 1))[0]  # positive floats order like their bits
    return value


@dataclass(frozen=True)
class Scaled:
    """A command after the override: ``command`` is what to send; ``clamped`` says a speed
    would have passed the profile's limit and was held to it."""

    command: Command
    clamped: bool = False


def scale_speed(command: Command, percent: int, speed_limits) -> Scaled:
    """``command`` with every speed slot × ``percent`` / 100, clamped to L201's limit for its
    type under ``speed_limits`` (the profile's ``Speeds``)."""
    names = SPEED_FIELDS.get(type(command))
    if percent == 100 or not names:
        return Scaled(command)
    limit = _f32_at_most(speed_limit(type(command), speed_limits))
    changes, clamped = {}, False
    for name in names:
        value = getattr(command, name)
        scaled = as_f32(value * percent / 100)  # what the slot would carry (value ≤ 2× a float32)
        if value > 0:
            scaled = max(scaled, _SMALLEST_F32)
        if scaled > limit:  # a job that passed lint has value ≤ limit; never faster than written
            scaled, clamped = (limit if value <= limit else min(scaled, value)), True
        changes[name] = scaled
    return Scaled(replace(command, **changes), clamped)


class FeedOverride:
    """The override a running job applies to each frame it writes; ``percent`` changes at
    any time, an arc's two frames keep the percentage of its first."""

    def __init__(self, speed_limits, percent: int = 100) -> None:
        self.speed_limits = speed_limits
        self.percent = clamp_percent(percent)
        self.clamped = False  # the last frame scaled was held to the profile's limit
        self._arc_percent: int | None = None

    def set_percent(self, percent: int) -> int:
        self.percent = clamp_percent(percent)
        return self.percent

    def step(self, steps: int) -> int:
        """+1 / −1: one FEED_STEP_PERCENT up or down."""
        return self.set_percent(self.percent + steps * FEED_STEP_PERCENT)

    def apply(self, command: Command) -> Command:
        percent = self.percent
        if isinstance(command, ArcStart):
            self._arc_percent = percent
        elif isinstance(command, ArcEnd) and self._arc_percent is not None:
            percent = self._arc_percent  # a G301 always follows its G300, which set this
        result = scale_speed(command, percent, self.speed_limits)
        if type(command) in SPEED_FIELDS:
            self.clamped = result.clamped
        return result.command
