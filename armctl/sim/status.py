"""The arm's status output: one 9-byte frame every 30 ms, rotating through the nine kinds.

Strategy: ``StatusSchedule`` knows *when* (frame ``n`` is built at ``n · STATUS_PERIOD_S``) and
*which kind* (``STATUS_ROTATION[n mod 9]``); ``build_status`` knows *what* (``status_bytes``, its bytes), from an
``ArmSnapshot`` (or any object with its attributes — the executor's is lazy, so a frame
reading only the pause state samples no pose) taken at that very moment.  Values are clamped to what a status word
can carry (a 16-bit word overflows at ±3276.7 mm or ±327.67°), so a wild pose never raises.
The frames are built with the codec in ``armctl.protocol``: the simulator and the reader share
one byte map.  Pure: no clock, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..protocol import (
    DEG_SCALE,
    MM_SCALE,
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    FileLengthStatus,
    FileStatus,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PositionStatus,
    RunPositionStatus,
    StatusFrame,
    WorktableStatus,
    WristStatus,
)

# The status value the arm reports while paused (kind 4, d1); 0 when running.
PAUSED_STATE_BYTE = 1
_WORD_MAX = 32767


@dataclass(frozen=True)
class ArmSnapshot:
    """What the status frames report, at one instant."""

    position_mm: tuple[float, float, float]  # tool X, Y, Z in worktable coordinates
    joints_deg: tuple[float, ...]  # joints 1…6
    origin_mm: tuple[float, float, float]  # worktable origin in robot coordinates
    paused: bool
    pwm_us: float
    program_length: float  # SD program file length
    program_status: int  # SD program file status (raw 16-bit)
    program_position: float  # SD program run position


def _clamp(value: float, scale: int) -> float:
    limit = _WORD_MAX / scale
    return max(-limit, min(limit, value))


def _mm(values) -> list[float]:
    return [_clamp(v, MM_SCALE) for v in values]


def _deg(values) -> list[float]:
    return [_clamp(v, DEG_SCALE) for v in values]


# The kinds carried as three (or two) status words: their frame and the values they report.
_WORD_KINDS = {
    0: (PositionStatus, lambda snapshot: _mm(snapshot.position_mm)),
    1: (JointsLowStatus, lambda snapshot: _deg(snapshot.joints_deg[0:3])),
    2: (JointsHighStatus, lambda snapshot: _deg(snapshot.joints_deg[3:6])),
    3: (WorktableStatus, lambda snapshot: _mm(snapshot.origin_mm)),
    5: (WristStatus, lambda snapshot: _deg(snapshot.joints_deg[3:5])),
}


def build_status(kind: int, snapshot: ArmSnapshot) -> StatusFrame:
    """The status frame of ``kind`` describing ``snapshot``."""
    words = _WORD_KINDS.get(kind)
    if words is not None:
        frame_class, values = words
        return frame_class(*values(snapshot))
    if kind == 4:
        pwm_us = int(round(max(-32768, min(_WORD_MAX, snapshot.pwm_us))))
        return PauseStatus(PAUSED_STATE_BYTE if snapshot.paused else 0, pwm_us)
    if kind == 100:
        return FileLengthStatus(snapshot.program_length)
    if kind == 102:
        return FileStatus(max(0, min(0xFFFF, snapshot.program_status)))
    if kind == 103:
        return RunPositionStatus(snapshot.program_position)
    raise ValueError(f"no status kind {kind}")


def status_bytes(kind: int, snapshot: ArmSnapshot) -> bytes:
    """``build_status(kind, snapshot).encode()``, the word kinds packed straight from their
    values (``encode_values``: the same bytes without building a frame, 40,000 in 20 minutes)."""
    words = _WORD_KINDS.get(kind)
    if words is not None:
        frame_class, values = words
        return frame_class.encode_values(*values(snapshot))
    return build_status(kind, snapshot).encode()


class StatusSchedule:
    """Frame ``n`` is due at ``first_s + n · period_s`` and is of kind ``rotation[n mod 9]``."""

    def __init__(self, period_s: float = STATUS_PERIOD_S, first_s: float = 0.0, rotation=STATUS_ROTATION) -> None:
        self.period_s = period_s
        self.first_s = first_s
        self.rotation = tuple(rotation)
        self.count = 0  # frames built so far

    @property
    def next_s(self) -> float:
        return self.first_s + self.count * self.period_s

    def pop(self) -> int:
        """The kind of the frame due at ``next_s``; moves on to the next one."""
        kind = self.rotation[self.count % len(self.rotation)]
        self.count += 1
        return kind
