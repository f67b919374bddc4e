"""The eight control commands (0xFC … 0xFD frames): a[1], a[2] select one, an argument follows.

Strategy: as armctl/core/motion_commands.py — frozen ``record`` classes checked and normalised on
construction, ``encode`` giving the 48 bytes and ``_from_frame`` the one inverse — with the
numbers and field checks of armctl/core/frame_fields.py.  armctl/core/protocol.py is the façade.
"""

from __future__ import annotations

from typing import ClassVar

from ..errors import FieldError, FrameError
from .frame_fields import (
    CONTROL_HEAD, CONTROL_TAIL, FIXED_POSE_RANGE, FLOAT_CODEC, FRAME_SIZE, JOYSTICK_JOINT_AXES, JOYSTICK_LINEAR_AXIS,
    JOYSTICK_STILL_RANGE, PAUSE_TOGGLE_ARGUMENT, PROGRAM_RANGE, STRUCTURE_MODE_ARGUMENT, Command, f32_field, int_field,
    slot_offset,
)
from .records import record


class _ControlCommand(Command):
    """A 0xFC … 0xFD frame: a[1], a[2] binary bytes, then an argument in a[3…]."""

    A1: ClassVar[int] = 0
    A2: ClassVar[int] = 0

    def _argument_bytes(self) -> bytes:
        return b""

    def encode(self) -> bytes:
        frame = bytearray(FRAME_SIZE)
        frame[0], frame[1], frame[2], frame[47] = CONTROL_HEAD, self.A1, self.A2, CONTROL_TAIL
        argument = self._argument_bytes()
        frame[3 : 3 + len(argument)] = argument
        return bytes(frame)

    @classmethod
    def _from_frame(cls, frame: bytes) -> "_ControlCommand":
        return cls()


@record
class ResetArm(_ControlCommand):
    """Control 12/3 — reset the arm (RESET)."""

    NAME: ClassVar[str] = "reset arm"
    A1: ClassVar[int] = 12
    A2: ClassVar[int] = 3


@record
class ResetConnector(_ControlCommand):
    """Control 12/6 — reset the host connector (RESET CONNECTOR)."""

    NAME: ClassVar[str] = "reset connector"
    A1: ClassVar[int] = 12
    A2: ClassVar[int] = 6


@record
class SetWorktableOrigin(_ControlCommand):
    """Control 20/1 — later coordinates are relative to robot point (X0, Y0, Z0) (G54)."""

    NAME: ClassVar[str] = "set worktable origin"
    A1: ClassVar[int] = 20
    A2: ClassVar[int] = 1

    x_mm: float
    y_mm: float
    z_mm: float

    def __post_init__(self) -> None:
        for name in ("x_mm", "y_mm", "z_mm"):
            object.__setattr__(self, name, f32_field("SetWorktableOrigin", name, getattr(self, name)))

    def _argument_bytes(self) -> bytes:
        return b"".join(FLOAT_CODEC.pack(v) for v in (self.x_mm, self.y_mm, self.z_mm))

    @classmethod
    def _from_frame(cls, frame: bytes) -> "SetWorktableOrigin":
        return cls(*(FLOAT_CODEC.unpack_from(frame, slot_offset(k))[0] for k in (1, 2, 3)))


@record
class RunProgram(_ControlCommand):
    """Control 30/2 — run an SD-card program: 0 the taught one, 1…15 Route_a…Route_o (PROGRAM n)."""

    NAME: ClassVar[str] = "run SD program"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 2

    program: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "program", int_field("RunProgram", "program", self.program, *PROGRAM_RANGE))

    def _argument_bytes(self) -> bytes:
        return bytes([self.program])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "RunProgram":
        return cls(frame[3])


@record
class PauseToggle(_ControlCommand):
    """Control 30/3, a[3]=2 — the first frame pauses, the next resumes (PAUSE)."""

    NAME: ClassVar[str] = "pause toggle"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 3

    def _argument_bytes(self) -> bytes:
        return bytes([PAUSE_TOGGLE_ARGUMENT])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "PauseToggle":
        if frame[3] != PAUSE_TOGGLE_ARGUMENT:
            raise FrameError(f"pause frame argument is {frame[3]}, expected {PAUSE_TOGGLE_ARGUMENT}")
        return cls()


@record
class GoToPose(_ControlCommand):
    """Control 30/5 — go to fixed pose 0…3 (POSE n)."""

    NAME: ClassVar[str] = "go to fixed pose"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 5

    pose: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "pose", int_field("GoToPose", "pose", self.pose, *FIXED_POSE_RANGE))

    def _argument_bytes(self) -> bytes:
        return bytes([self.pose])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "GoToPose":
        return cls(frame[3])


@record
class Joystick(_ControlCommand):
    """Control 30/7 — analog joystick.

    ``axis`` 0…5 turns joint 1…6 by ``values[0]``; axis 100 moves the tool in a straight line
    with ``values`` = (X, Y, Z).  Each value is a byte: 108…148 stands still, lower turns
    towards smaller angles (lower = faster), higher towards larger ones.
    """

    NAME: ClassVar[str] = "joystick"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 7

    axis: int
    values: tuple[int, ...]

    def __post_init__(self) -> None:
        axis = int_field("Joystick", "axis", self.axis, 0, JOYSTICK_LINEAR_AXIS)
        if axis not in JOYSTICK_JOINT_AXES and axis != JOYSTICK_LINEAR_AXIS:
            raise FieldError(f"Joystick.axis = {axis} is neither a joint (0…5) nor linear (100)")
        values = tuple(self.values) if isinstance(self.values, (tuple, list)) else (self.values,)
        wanted = 3 if axis == JOYSTICK_LINEAR_AXIS else 1
        if len(values) != wanted:
            raise FieldError(f"Joystick axis {axis} takes {wanted} value(s), not {len(values)}")
        values = tuple(int_field("Joystick", "values", v, 0, 255) for v in values)
        object.__setattr__(self, "axis", axis)
        object.__setattr__(self, "values", values)

    @property
    def is_still(self) -> bool:
        low, high = JOYSTICK_STILL_RANGE
        return all(low <= v <= high for v in self.values)

    def _argument_bytes(self) -> bytes:
        return bytes([self.axis, *self.values])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "Joystick":
        axis = frame[3]
        count = 3 if axis == JOYSTICK_LINEAR_AXIS else 1
        return cls(axis, tuple(frame[4 : 4 + count]))


@record
class StructureMode(_ControlCommand):
    """Control 30/9 — structure mode 0 (a[3]=0) or 1 (a[3]=9) (MODE 0 / MODE 1)."""

    NAME: ClassVar[str] = "structure mode"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 9

    mode: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", int_field("StructureMode", "mode", self.mode, 0, 1))

    def _argument_bytes(self) -> bytes:
        return bytes([STRUCTURE_MODE_ARGUMENT[self.mode]])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "StructureMode":
        for mode, argument in STRUCTURE_MODE_ARGUMENT.items():
            if frame[3] == argument:
                return cls(mode)
        raise FrameError(f"structure mode argument is {frame[3]}, expected 0 or 9")
