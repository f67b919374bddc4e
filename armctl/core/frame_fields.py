"""What every frame of the protocol shares: the wire's numbers, how a field becomes what the
wire holds, and the base of the host→arm commands.

Strategy: the bottom of the protocol's modules (armctl/core/protocol.py is their façade).  The
command modules (armctl/core/motion_commands.py, armctl/core/control_commands.py) and the status frames
(armctl/core/status_frames.py) import their constants and their field checks from here, downwards,
so none of them needs another's module to exist first.  A field is *normalised* on the way in:
``f32_field`` rounds a number to IEEE single precision (H1) or raises the FieldError that names
the field; ``int_field`` and ``check_range`` likewise.  Bytes and nothing else: no port, no
clock, no I/O.  Every H-label of PROTOCOL.md that concerns bytes is one named constant here.
"""

from __future__ import annotations

import math
import struct
from dataclasses import fields
from typing import ClassVar

from ..errors import FieldError
# The link's numbers live in armctl/core/line.py (imported without the codec: the CLI's option ranges
# derive from them at start-up); they are part of this module's interface too.
from .line import (  # noqa: F401
    BITS_PER_BYTE, CONNECTOR_BUFFER_BYTES, CONNECTOR_BUFFER_FRAMES, DEFAULT_BAUD, FRAME_SIZE, STATUS_PERIOD_S, STATUS_SIZE,
)

# --- the link -------------------------------------------------------------------------------


def byte_seconds(baud: int = DEFAULT_BAUD) -> float:
    """Seconds one byte occupies on the wire at ``baud`` (8N1)."""
    return BITS_PER_BYTE / baud


def frame_seconds(baud: int = DEFAULT_BAUD) -> float:
    """Seconds one 48-byte command frame occupies on the wire: 50 ms at 9600 baud."""
    return FRAME_SIZE * byte_seconds(baud)


MOTION_HEAD, MOTION_TAIL = 0xEE, 0xEF
CONTROL_HEAD, CONTROL_TAIL = 0xFC, 0xFD
STATUS_HEAD, STATUS_TAIL = 0xCE, 0xCF

# H1 — floats are IEEE-754 single precision, little-endian.
FLOAT_CODEC = struct.Struct("<f")
# H4 — the M number is a 32-bit little-endian signed integer in a[3..6].
M_CODE_CODEC = struct.Struct("<i")
# H8 — 16-bit status values are signed (two's complement), big-endian; the two status
# floats (file length, run position) are little-endian like H1 (FLOAT_CODEC).
STATUS_WORD_CODEC = struct.Struct(">h")
# PROTOCOL.md: a[2] = 0 or 1 both select PWM channel 1 in a linear move; armctl sends 1,
# the value the vendor's own table shows.
LINEAR_SUBCOMMAND_FOR_CHANNEL_1 = 1
# H5 (control frames wait in the same FIFO as motion frames) and H6 (the FIFO's size) are not
# constants: they are the arm profile's [connector] settings, the document's reading by default.

# Protocol ranges (PROTOCOL.md); a command outside them cannot be constructed.
PWM_RANGE_US = (500.0, 2500.0)
ACCEL_RANGE_MM_S2 = (-3200.0, 3200.0)
SMOOTHING_RANGE = (0, 6)
PWM_CHANNELS = (1, 2, 3, 4)
PROGRAM_RANGE = (0, 15)
FIXED_POSE_RANGE = (0, 3)
JOYSTICK_JOINT_AXES = range(0, 6)  # joints 1…6
JOYSTICK_LINEAR_AXIS = 100  # a[4..6] drive X, Y, Z
JOYSTICK_NEUTRAL = 128
JOYSTICK_STILL_RANGE = (108, 148)  # inclusive: values here mean "stand still"
PAUSE_TOGGLE_ARGUMENT = 2
STRUCTURE_MODE_ARGUMENT = {0: 0, 1: 9}  # mode → a[3]


# --- field normalisation ----------------------------------------------------------------------


def f32_field(cls_name: str, name: str, value) -> float:
    """``value`` as the single-precision float a frame's field holds (H1); FieldError names the
    field when it is no number, not finite or beyond float32."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FieldError(f"{cls_name}.{name} must be a number, not {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise FieldError(f"{cls_name}.{name} must be finite, not {value!r}")
    single = as_f32(value)
    if single is None:  # beyond what rounds to ±float32 max (≈3.4028235e38)
        raise FieldError(f"{cls_name}.{name} = {value!r} does not fit a 32-bit float")
    return single


def int_field(cls_name: str, name: str, value, low: int, high: int) -> int:
    """``value`` as a whole number within ``low``…``high`` (a whole float accepted); else FieldError."""
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise FieldError(f"{cls_name}.{name} must be a whole number, not {value!r}")
    if not low <= value <= high:
        raise FieldError(f"{cls_name}.{name} = {value} is outside {low}…{high}")
    return value


def check_range(cls_name: str, name: str, value: float, low: float, high: float) -> None:
    """FieldError unless ``low`` ≤ ``value`` ≤ ``high``, the numbers spelt as the wire holds them."""
    if not low <= value <= high:
        raise FieldError(f"{cls_name}.{name} = {f32_repr(value)} is outside {f32_repr(low)}…{f32_repr(high)}")


def as_f32(value: float) -> float | None:
    """``value`` rounded to single precision (H1), or None when it rounds beyond ±float32 max.

    The one place that asks "what would the wire hold?": ``struct`` refuses a double that
    rounds past the largest float32 with OverflowError, which must never reach a user."""
    try:
        return FLOAT_CODEC.unpack(FLOAT_CODEC.pack(value))[0]
    except OverflowError:
        return None


def f32_repr(value: float) -> str:
    """The shortest decimal that reads back as the same single-precision float.

    Total over every float: ±inf and NaN (which a frame being decoded may carry) are spelt
    ``inf``, ``-inf`` and ``nan``; a double that is no float32 gets its own ``repr``."""
    value = float(value)
    if not math.isfinite(value):
        return repr(value)
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    for digits in range(1, 10):
        text = f"{value:.{digits}g}"
        if as_f32(float(text)) == value:
            return text
    return repr(value)


def slot_offset(slot: int) -> int:
    """The byte offset of a command frame's float slot 1…11: a[3 + 4·(slot − 1)]."""
    return 3 + 4 * (slot - 1)


# --- host → arm commands ----------------------------------------------------------------------

# Every command is a frozen dataclass (``record``: its __eq__, __hash__ and __repr__ shared, not
# compiled for each class at import; armctl/core/records.py).  The three bases — Command here,
# _MotionCommand and _ControlCommand with their commands — have no fields and are never built,
# so they are plain classes: a frozen dataclass may extend a plain class.


class Command:
    """Base of the 15 host→arm commands."""

    NAME: ClassVar[str] = ""

    def encode(self) -> bytes:  # pragma: no cover - every subclass overrides
        raise NotImplementedError

    def fields(self) -> dict:
        """The command's fields by name, in declaration order."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

