"""The motion model's time: a path's distance as a function of time, pieces of constant acceleration.

Strategy: every timed motion is a ``Ramp`` — at most three pieces, each (distance, speed at its
start, speed at its end) — and ``distance_at`` / ``time_at`` evaluate it in closed form.  The
rules that choose the pieces (an AccelLinearMove's mode, a joint move's start and stop ramps)
are ``accel_pieces`` and ``joint_pieces``; armctl/core/motion.py's docstring states them, and its
planner is the one caller that builds ramps from commands.  Plain floats; no clock, no I/O.
"""

from __future__ import annotations

import math
from typing import Sequence

_sqrt = math.sqrt


def piece_s(distance: float, v_from: float, v_to: float) -> float:
    """Seconds to cover ``distance`` at constant acceleration from ``v_from`` to ``v_to``."""
    return 2.0 * distance / (v_from + v_to)


def stretch(path_s: float, other_s: float) -> float:
    """The factor a path's seconds are stretched by so that the attitude and the E axes, which
    need ``other_s``, finish with it."""
    return other_s / path_s if other_s > path_s > 0 else 1.0


def mm_s(speed_mm_min: float, limit_mm_min: float) -> float:
    """A Cartesian speed in mm/s, clamped to the profile's maximum."""
    return min(speed_mm_min, limit_mm_min) / 60.0


class Ramp:
    """Distance along a path as a function of time: pieces of constant acceleration."""

    __slots__ = ("length", "duration", "_pieces")

    def __init__(self, pieces: Sequence[tuple[float, float, float]]):
        """``pieces``: (distance, speed at its start, speed at its end); speeds must not both be 0."""
        t = s = 0.0
        out = []
        for distance, v_from, v_to in pieces:
            if distance > 0:
                dt = piece_s(distance, v_from, v_to)
                out.append((t, s, v_from, (v_to - v_from) / dt))
                t += dt
                s += distance
        self.length, self.duration, self._pieces = s, t, tuple(reversed(out))

    @classmethod
    def constant(cls, length: float, duration: float) -> "Ramp":
        return cls([(length, length / duration, length / duration)] if duration > 0 else [])

    def distance_at(self, t: float) -> float:
        if t >= self.duration:
            return self.length
        for t0, s0, v0, a in self._pieces:
            if t >= t0:
                dt = t - t0
                s = s0 + v0 * dt + 0.5 * a * dt * dt
                return self.length if self.length < s else s  # min(s, length), without the call
        return 0.0

    def time_at(self, s: float) -> float:
        if s >= self.length:
            return self.duration
        for t0, s0, v0, a in self._pieces:
            if s >= s0:
                ds = s - s0
                if ds > 0:
                    square = v0 * v0 + 2.0 * a * ds
                    # sqrt(max(square, 0.0)) without the max call: square unless 0.0 is greater
                    return t0 + 2.0 * ds / (v0 + _sqrt(0.0 if 0.0 > square else square))
                return t0
        return 0.0


def accel_pieces(mode: int, length: float, accel: float, v1: float, v0: float):
    """Pieces of an AccelLinearMove (mm, mm/s, mm/s²), see the module docstring."""
    a = abs(accel)
    ramp = v1 * v1 / (2.0 * a)
    if mode == 0 and accel > 0:
        return [(length, 0.0, math.sqrt(2 * a * length))] if ramp >= length else [(ramp, 0.0, v1), (length - ramp, v1, v1)]
    if mode == 0:
        return [(length, math.sqrt(2 * a * length), 0.0)] if ramp >= length else [(length - ramp, v1, v1), (ramp, v1, 0.0)]
    if mode == 1:
        if 2 * ramp >= length:
            peak = math.sqrt(a * length)
            return [(length / 2, 0.0, peak), (length / 2, peak, 0.0)]
        return [(ramp, 0.0, v1), (length - 2 * ramp, v1, v1), (ramp, v1, 0.0)]
    ramp = abs(v1 * v1 - v0 * v0) / (2.0 * a)
    if ramp >= length:
        sign = 1.0 if v1 >= v0 else -1.0
        return [(length, v0, math.sqrt(max(v0 * v0 + sign * 2 * a * length, 0.0)))]
    return [(ramp, v0, v1), (length - ramp, v1, v1)]


def joint_pieces(lead_deg: float, speed: float, ramp_s: float):
    if ramp_s <= 0:
        return [(lead_deg, speed, speed)]
    ramp = speed * ramp_s / 2.0  # distance covered while ramping at speed / ramp_s
    if 2 * ramp >= lead_deg:
        peak = math.sqrt(speed / ramp_s * lead_deg)
        return [(lead_deg / 2, 0.0, peak), (lead_deg / 2, peak, 0.0)]
    return [(ramp, 0.0, speed), (lead_deg - 2 * ramp, speed, speed), (ramp, speed, 0.0)]


NO_MOTION = Ramp([])
