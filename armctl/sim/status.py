"""The arm's status output: one 9-byte frame every 30 ms, rotating through the nine kinds.

Strategy: ``StatusSchedule`` knows *when* (frame ``n`` is built at ``n · STATUS_PERIOD_S``) and
*which kind* (``STATUS_ROTATION[n mod 9]``); ``build_status`` knows *what* (``status_bytes``, its bytes), from an
``ArmSnapshot`` (or any object with its attributes — the executor's is lazy, so a frame
reading only the pause state samples no pose) taken at that very moment.  Values are clamped to what a status word
can carry (a 16-bit word overflows at ±3276.7 mm or ±327.67°), so a wild pose never raises.
The frames are built with the codec in ``armctl.core.protocol``: the simulator and the reader share
one byte map.  Pure: no clock, no I/O.
"""

from __future__ import annotations

import random
import struct
from dataclasses import dataclass

from ..core.protocol import (
    DEG_SCALE,
    MM_SCALE,
    STATUS_PERIOD_S,
    STATUS_HEAD,
    STATUS_ROTATION,
    STATUS_TAIL,
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


def _word_struct(frame_class) -> struct.Struct:
    """The whole 9-byte frame of a word kind, head to tail, as one precompiled ``Struct``: the
    codec ``encode_values`` packs after the head byte, with the head in front."""
    frame_class._field_names()  # builds the class's codec
    codec = frame_class._codec
    return struct.Struct(codec.format[0] + "B" + codec.format[1:])


class StatusEncoder:
    """``status_bytes`` for the simulator's event loop (one frame per 30 ms, 40,000 in 20
    minutes), read straight from the executor: each kind reads only what it reports (no
    snapshot object; the pose sampled only for the kinds that report it, its joints — IK on a
    Cartesian path — only for kinds 1, 2 and 5), a word kind is packed head to tail with one
    precompiled ``Struct``, and a kind whose value seldom changes (worktable origin, pause and
    PWM, SD file length, status and run position) reuses the bytes it built for the same value.
    The same bytes as ``status_bytes(kind, executor.snapshot(at_s))`` by construction — the
    same clamping and rounding, value by value (tests/test_sim_status_encoder.py holds them equal)."""

    def __init__(self) -> None:
        # kind → (its Struct, its scale, _clamp's limit)
        self._structs = {kind: (_word_struct(cls), cls.SCALE, _WORD_MAX / cls.SCALE) for kind, (cls, _) in _WORD_KINDS.items()}
        self._built: dict[int, tuple] = {}  # kind → (the value, its bytes) for the seldom-changing kinds
        self._by_kind = {0: self._position, 1: self._joints_low, 2: self._joints_high, 3: self._worktable,
                         4: self._pause, 5: self._wrist, 100: self._file_length, 102: self._file_status,
                         103: self._run_position}

    def encode(self, kind: int, executor, at_s: float) -> bytes:
        encode = self._by_kind.get(kind)
        if encode is None:
            raise ValueError(f"no status kind {kind}")
        return encode(executor, at_s)

    def encode_steps(self, executor, steps: list) -> list[bytes]:
        """``encode`` of each step (kind, due time) of ``SimulatedArm.status_run``'s ``steps``."""
        by_kind, encode = self._by_kind, self.encode  # (encode: what it says of an unknown kind)
        return [by_kind[kind](executor, due_s) if kind in by_kind else encode(kind, executor, due_s)
                for _, kind, due_s, _, _ in steps]

    # One method a kind (``_by_kind``).  A pose kind takes the values of the pose from
    # ``executor.cartesian_at`` while a line or an arc runs between its ends (the pose
    # ``Segment.sample`` would build: worktable Cartesian values, its origin, PWM and IK hint the
    # segment ``end``'s; no pose objects), else from ``executor.pose_at`` — the same sums as
    # ``ArmPose.robot_cartesian`` and the IK of ``ArmPose.joints`` (``Kinematics.joints_of``),
    # so the same floats either way.

    def _position(self, executor, at_s: float) -> bytes:
        on_path = executor.cartesian_at(at_s)
        if on_path is not None:
            cartesian, end = on_path
            po = end.origin_mm
        else:
            pose = executor.pose_at(at_s)
            cartesian, po = pose.cartesian, pose.origin_mm
        x, y, z = cartesian[0] + po[0], cartesian[1] + po[1], cartesian[2] + po[2]  # robot_cartesian's sums
        if not executor.reports_robot_xyz:
            ox, oy, oz = executor.origin_mm
            x, y, z = x - ox, y - oy, z - oz
        return self._words3(0, x, y, z)

    @staticmethod
    def _joints(executor, at_s: float) -> tuple[float, ...]:
        on_path = executor.cartesian_at(at_s)
        if on_path is None:
            return executor.pose_at(at_s).joints
        (x, y, z, b0, b1, w), end = on_path
        po = end.origin_mm
        return end.kinematics.joints_of((x + po[0], y + po[1], z + po[2], b0, b1, w), end.ik_hint)

    def _joints_low(self, executor, at_s: float) -> bytes:
        joints = self._joints(executor, at_s)
        return self._words3(1, joints[0], joints[1], joints[2])

    def _joints_high(self, executor, at_s: float) -> bytes:
        joints = self._joints(executor, at_s)
        return self._words3(2, joints[3], joints[4], joints[5])

    def _wrist(self, executor, at_s: float) -> bytes:
        joints = self._joints(executor, at_s)
        return self._words2(5, joints[3], joints[4])

    def _worktable(self, executor, at_s: float) -> bytes:
        origin = executor.origin_mm
        return self._reused(3, origin) or self._keep(3, origin, self._words3(3, *origin))

    def _pause(self, executor, at_s: float) -> bytes:
        on_path = executor.cartesian_at(at_s)
        pwm_us = (executor.pose_at(at_s) if on_path is None else on_path[1]).pwm_us[0]
        pwm_us = int(round(max(-32768, min(_WORD_MAX, pwm_us))))
        key = (executor.paused, pwm_us)
        return self._reused(4, key) or self._keep(4, key, PauseStatus(PAUSED_STATE_BYTE if key[0] else 0, pwm_us).encode())

    def _program(self, kind: int, value) -> bytes:
        # a float's hex tells -0.0 from 0.0 (equal, but packed differently)
        key = value.hex() if type(value) is float else value
        return self._reused(kind, key) or self._keep(kind, key, build_status(kind, _ProgramValue(value)).encode())

    def _file_length(self, executor, at_s: float) -> bytes:
        return self._program(100, executor.program.length)

    def _file_status(self, executor, at_s: float) -> bytes:
        return self._program(102, executor.program.status_at(at_s))

    def _run_position(self, executor, at_s: float) -> bytes:
        return self._program(103, executor.program.position_at(at_s))

    # A word: _clamp's ``max(-limit, min(limit, v))`` written out (``min`` keeps ``limit`` unless
    # v < limit, NaN included; ``max`` keeps ``-limit`` unless v > -limit), then _raw_word's
    # float × scale, rounded — the same ints without two builtin calls and a list per word.

    def _words3(self, kind: int, a, b, c) -> bytes:
        codec, scale, limit = self._structs[kind]
        low = -limit
        a = a if a < limit else limit
        b = b if b < limit else limit
        c = c if c < limit else limit
        return codec.pack(STATUS_HEAD, round(float(a if a > low else low) * scale),
                          round(float(b if b > low else low) * scale), round(float(c if c > low else low) * scale),
                          kind, STATUS_TAIL)

    def _words2(self, kind: int, a, b) -> bytes:
        codec, scale, limit = self._structs[kind]
        low = -limit
        a = a if a < limit else limit
        b = b if b < limit else limit
        return codec.pack(STATUS_HEAD, round(float(a if a > low else low) * scale),
                          round(float(b if b > low else low) * scale), kind, STATUS_TAIL)

    # A seldom-changing kind: the bytes built for the same value last time (``_reused``, None if
    # it changed), else built and kept (``_keep``) — no builder made for a frame that reuses them.

    def _reused(self, kind: int, key) -> bytes | None:
        built = self._built.get(kind)
        if built is not None and built[0] == key and type(built[0]) is type(key):
            return built[1]
        return None

    def _keep(self, kind: int, key, data: bytes) -> bytes:
        self._built[kind] = (key, data)
        return data


class _ProgramValue:
    """The one value an SD-program status kind reports, under every name build_status reads."""

    def __init__(self, value) -> None:
        self.program_length = self.program_status = self.program_position = value


class StatusSchedule:
    """Frame ``n`` is due at ``first_s + n · period_s`` and is of kind ``rotation[n mod 9]``; an
    arm whose own loop is late (``jitter_s``) builds each one up to that much later (uniform,
    drawn from ``seed``)."""

    def __init__(self, period_s: float = STATUS_PERIOD_S, first_s: float = 0.0, rotation=STATUS_ROTATION,
                 jitter_s: float = 0.0, seed: int = 0) -> None:
        self.period_s = period_s
        self.first_s = first_s
        self.rotation = tuple(rotation)
        self.count = 0  # frames built so far
        self.jitter_s = jitter_s
        self._late = random.Random(seed) if jitter_s else None
        self._late_s = self._late.uniform(0.0, jitter_s) if self._late else 0.0  # the next frame's

    @property
    def next_s(self) -> float:
        return self.first_s + self.count * self.period_s + self._late_s

    def pop(self) -> int:
        """The kind of the frame due at ``next_s``; moves on to the next one."""
        kind = self.rotation[self.count % len(self.rotation)]
        self.count += 1
        if self._late:
            self._late_s = self._late.uniform(0.0, self.jitter_s)
        return kind
