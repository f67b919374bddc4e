"""The arm's serial protocol: every frame as an immutable object ⇄ its exact bytes.

Strategy (after h11): this module knows bytes and nothing else — no port, no clock, no I/O.
Host→arm commands are frozen dataclasses whose fields carry their units in their names
(``x_mm``, ``speed_mm_min``); ``encode()`` gives the 48 bytes and ``decode_command()`` is the
one inverse.  Arm→host status frames likewise, with ``decode_status()`` and a ``StatusReader``
that is fed arbitrary chunks and resynchronises after noise.

Fields are validated and *normalised* on construction: floats are rounded to IEEE single
precision, status values to their wire resolution.  So an object holds exactly what will be
on the wire, and ``decode(encode(x)) == x`` for every valid ``x``.

Every hypothesis PROTOCOL.md labels H1…H9 that concerns bytes lives here as one named
constant or function, marked with its label; the README lists where each one lives.  Status
frames, finding frames in a byte stream and the readable form live in armctl/status_frames.py,
imported on first use (this module offers their names too): compile and lint never build them.
"""

from __future__ import annotations

import math
import operator
import struct
from dataclasses import dataclass, fields
from typing import ClassVar, Union

from .errors import FieldError, FrameError
from .records import record

# --- the link -------------------------------------------------------------------------------

# The link's numbers live in armctl/line.py (imported without the codec: the CLI's option ranges
# derive from them at start-up); they are part of this module's interface too.
from .line import (  # noqa: E402,F401
    BITS_PER_BYTE, CONNECTOR_BUFFER_BYTES, CONNECTOR_BUFFER_FRAMES, DEFAULT_BAUD, FRAME_SIZE, STATUS_PERIOD_S, STATUS_SIZE,
)


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


def _f32(cls_name: str, name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FieldError(f"{cls_name}.{name} must be a number, not {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise FieldError(f"{cls_name}.{name} must be finite, not {value!r}")
    single = as_f32(value)
    if single is None:  # beyond what rounds to ±float32 max (≈3.4028235e38)
        raise FieldError(f"{cls_name}.{name} = {value!r} does not fit a 32-bit float")
    return single


_PLAIN_NUMBERS = frozenset((int, float))  # exact types: bool is refused, as _f32 does


def _int(cls_name: str, name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise FieldError(f"{cls_name}.{name} must be a whole number, not {value!r}")
    if not low <= value <= high:
        raise FieldError(f"{cls_name}.{name} = {value} is outside {low}…{high}")
    return value


def _check_range(cls_name: str, name: str, value: float, low: float, high: float) -> None:
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


# --- host → arm commands ----------------------------------------------------------------------

# Every command is a frozen dataclass (``record``: its __eq__, __hash__ and __repr__ shared, not
# compiled for each class at import; armctl/records.py).  The three bases have no fields and are
# never built, so they are plain classes: a frozen dataclass may extend a plain class.


class Command:
    """Base of the 15 host→arm commands."""

    NAME: ClassVar[str] = ""

    def encode(self) -> bytes:  # pragma: no cover - every subclass overrides
        raise NotImplementedError

    def fields(self) -> dict:
        """The command's fields by name, in declaration order."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


class _MotionCommand(Command):
    """A 0xEE … 0xEF frame: a[1] an ASCII command character, a[2] a sub-command byte and up
    to eleven float slots f1…f11 at a[3 + 4·(k−1)]."""

    CODE: ClassVar[str] = ""
    # field name → float slot 1…11; fields not listed are integers handled by the subclass.
    SLOTS: ClassVar[dict[str, int]] = {}

    _FIELD_NAMES: ClassVar[tuple] = ()  # from_fields: set below for each command

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        # not annotated: no dataclass fields
        cls._FLOAT_NAMES = names = tuple(cls.SLOTS)
        cls._FLOATS_CODEC = struct.Struct(f"<{len(names)}f")  # H1, all float fields at once
        # itemgetter of one name gives the value, not a 1-tuple; a lambda would bind as a method
        one = staticmethod(lambda state: (state[names[0]],))
        cls._floats_of = operator.itemgetter(*names) if len(names) > 1 else one
        # The whole frame in one pack (a compiler encodes one per line): head, command
        # character, sub-command, the eleven slots (zero bytes where no field is), tail.
        by_slot = {slot: name for name, slot in cls.SLOTS.items()}
        cls._FRAME_CODEC = struct.Struct("<3B" + "".join("f" if k in by_slot else "4x" for k in range(1, 12)) + "B")
        cls._slot_values = operator.itemgetter(*(by_slot[k] for k in sorted(by_slot))) if len(by_slot) > 1 else one

    @classmethod
    def from_fields(cls, *values):
        """``cls(*values)`` with every field given, in declaration order, built without the
        frozen dataclass's one ``object.__setattr__`` per field (a compiler builds one per
        line): the same object, the same checks, the same FieldError.  When every float field
        is a ``float`` it is straight-line code compiled once per class (``_compile_from_fields``):
        one pack/unpack rounds them all, one dict literal stores every field; anything else —
        an int, a bool, a value too large for float32, inf or NaN — is simply ``cls(*values)``."""
        build = cls.__dict__.get("_from_floats")
        if build is None:
            build = cls._compile_from_fields()
        return build(*values) if len(values) == len(cls._FIELD_NAMES) else cls(*values)

    @classmethod
    def fields_builder(cls):
        """``from_fields`` for a caller that always passes every field positionally (the
        compiler's hot path calls it once per line): the compiled function itself."""
        return cls.__dict__.get("_from_floats") or cls._compile_from_fields()

    @classmethod
    def _compile_from_fields(cls):
        names = cls._FIELD_NAMES
        floats = [name for name in names if name in cls.SLOTS]
        rounded = [f"r_{name}" for name in floats]
        given = ", ".join(names)
        value_of = dict(zip(floats, rounded))
        source = "\n".join([
            f"def from_floats({given}):",
            f"    if {' and '.join(f'{name}.__class__ is float' for name in floats)}:",
            "        try:",
            f"            {', '.join(rounded)}, = unpack(pack({', '.join(floats)}))",
            "        except OverflowError:",
            f"            return cls({given})",
            f"        if isfinite({' + '.join(rounded)}):",  # each at most float32's max: finite unless one is not
            "            self = new(cls)",
            f"            self.__dict__.update({{{', '.join(f'{name!r}: {value_of.get(name, name)}' for name in names)}}})",
            "            self._validate()",
            "            return self",
            f"    return cls({given})",
            "",
        ])
        codec = struct.Struct(f"<{len(floats)}f")  # H1
        namespace = {"cls": cls, "unpack": codec.unpack, "pack": codec.pack, "isfinite": math.isfinite,
                     "new": object.__new__}
        exec(compile(source, f"<{cls.__name__}.from_fields>", "exec"), namespace)  # noqa: S102 - our own source
        cls._from_floats = build = namespace["from_floats"]
        return build

    def __post_init__(self) -> None:
        # Every float field rounded to single precision in one pack/unpack and stored in one
        # update.  Anything unusual — a value
        # that is no plain int/float, not finite, or too large for float32 — takes the
        # field-by-field path, which raises the precise FieldError.
        state, names = self.__dict__, self._FLOAT_NAMES
        values = self._floats_of(state)
        rounded = None
        if set(map(type, values)) <= _PLAIN_NUMBERS:
            try:
                rounded = self._FLOATS_CODEC.unpack(self._FLOATS_CODEC.pack(*values))
            except (OverflowError, struct.error):  # struct.error: an int too large for a double
                pass
        # each rounded value is at most float32's max, so their sum is finite unless one is not
        if rounded is not None and math.isfinite(sum(rounded)):
            state.update(zip(names, rounded))
        else:
            for name in names:
                object.__setattr__(self, name, _f32(type(self).__name__, name, getattr(self, name)))
        self._validate()

    def _validate(self) -> None:
        pass

    def subcommand(self) -> int:
        return 0

    def encode(self) -> bytes:
        return self._FRAME_CODEC.pack(MOTION_HEAD, ord(self.CODE), self.subcommand(), *self._slot_values(self.__dict__),
                                      MOTION_TAIL)

    @classmethod
    def _from_frame(cls, frame: bytes) -> "_MotionCommand":
        values = {name: FLOAT_CODEC.unpack_from(frame, _slot_offset(slot))[0] for name, slot in cls.SLOTS.items()}
        return cls(**values, **cls._ints_from_subcommand(frame[2]))

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        return {}


def _slot_offset(slot: int) -> int:
    return 3 + 4 * (slot - 1)


_POSE_SLOTS = {"x_mm": 1, "y_mm": 2, "z_mm": 3, "b0_deg": 4, "b1_deg": 5, "w_deg": 6}
_EXTERNAL_SLOTS = {"e0_deg": 8, "e1_deg": 9}


def _check_pwm(obj) -> None:
    _check_range(type(obj).__name__, "pwm_us", obj.pwm_us, *PWM_RANGE_US)


def _check_positive(obj, name: str) -> None:
    if not getattr(obj, name) > 0:
        raise FieldError(f"{type(obj).__name__}.{name} must be greater than 0, not {f32_repr(getattr(obj, name))}")


def _check_not_negative(obj, name: str) -> None:
    if getattr(obj, name) < 0:
        raise FieldError(f"{type(obj).__name__}.{name} must not be negative, not {f32_repr(getattr(obj, name))}")


@record
class LinearMove(_MotionCommand):
    """'1' — the tool tip moves in a straight line to the pose (G1)."""

    NAME: ClassVar[str] = "linear move"
    CODE: ClassVar[str] = "1"
    SLOTS: ClassVar[dict[str, int]] = {**_POSE_SLOTS, "pwm_us": 7, **_EXTERNAL_SLOTS, "speed_mm_min": 11}

    x_mm: float
    y_mm: float
    z_mm: float
    b0_deg: float
    b1_deg: float
    w_deg: float
    pwm_us: float
    speed_mm_min: float
    e0_deg: float = 0.0
    e1_deg: float = 0.0
    pwm_channel: int = 1

    def _validate(self) -> None:
        # the common case inline (one per compiled line); anything else takes the checks that word the error
        channel, low, high = self.pwm_channel, *PWM_RANGE_US
        if channel.__class__ is not int or not 1 <= channel <= 4:
            object.__setattr__(self, "pwm_channel", _int("LinearMove", "pwm_channel", channel, 1, 4))
        if not low <= self.pwm_us <= high:
            _check_pwm(self)
        if not self.speed_mm_min > 0:
            _check_positive(self, "speed_mm_min")

    def subcommand(self) -> int:
        return LINEAR_SUBCOMMAND_FOR_CHANNEL_1 if self.pwm_channel == 1 else self.pwm_channel

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        if subcommand > 4:
            raise FrameError(f"linear move sub-command {subcommand} is not a PWM channel (0…4)")
        return {"pwm_channel": max(subcommand, 1)}


@record
class AccelLinearMove(_MotionCommand):
    """'2' — linear move with acceleration; ``mode`` is a[2] (G220 / G222 / G230 → 0 / 1 / 2).

    H2 — speed0 and speed1 are mm/min, like the plain linear move: the field names say so,
    and the motion-time model reads them through these names only.
    """

    NAME: ClassVar[str] = "accelerated linear move"
    CODE: ClassVar[str] = "2"
    SLOTS: ClassVar[dict[str, int]] = {
        **_POSE_SLOTS, "speed0_mm_min": 7, **_EXTERNAL_SLOTS, "accel_mm_s2": 10, "speed1_mm_min": 11,
    }

    mode: int
    x_mm: float
    y_mm: float
    z_mm: float
    b0_deg: float
    b1_deg: float
    w_deg: float
    accel_mm_s2: float
    speed1_mm_min: float
    speed0_mm_min: float = 0.0
    e0_deg: float = 0.0
    e1_deg: float = 0.0

    def _validate(self) -> None:
        object.__setattr__(self, "mode", _int("AccelLinearMove", "mode", self.mode, 0, 2))
        _check_range("AccelLinearMove", "accel_mm_s2", self.accel_mm_s2, *ACCEL_RANGE_MM_S2)
        _check_positive(self, "speed1_mm_min")
        _check_not_negative(self, "speed0_mm_min")
        if self.mode != 2 and self.speed0_mm_min != 0:
            raise FieldError(f"AccelLinearMove.speed0_mm_min is used in mode 2 only; mode {self.mode} sends 0")

    def subcommand(self) -> int:
        return self.mode

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        return {"mode": subcommand}


@record
class JointMove(_MotionCommand):
    """'3' — all six joints move synchronously to the angles (G6); a[2] = start/stop smoothing."""

    NAME: ClassVar[str] = "joint move"
    CODE: ClassVar[str] = "3"
    SLOTS: ClassVar[dict[str, int]] = {
        "j1_deg": 1, "j2_deg": 2, "j3_deg": 3, "j4_deg": 4, "j5_deg": 5, "j6_deg": 6,
        "pwm_us": 7, **_EXTERNAL_SLOTS, "speed_deg_s": 11,
    }

    j1_deg: float
    j2_deg: float
    j3_deg: float
    j4_deg: float
    j5_deg: float
    j6_deg: float
    pwm_us: float
    speed_deg_s: float
    e0_deg: float = 0.0
    e1_deg: float = 0.0
    smoothing: int = 0

    def _validate(self) -> None:
        object.__setattr__(self, "smoothing", _int("JointMove", "smoothing", self.smoothing, *SMOOTHING_RANGE))
        _check_pwm(self)
        _check_positive(self, "speed_deg_s")

    def subcommand(self) -> int:
        return self.smoothing

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        return {"smoothing": subcommand}

    @property
    def joints_deg(self) -> tuple[float, ...]:
        return (self.j1_deg, self.j2_deg, self.j3_deg, self.j4_deg, self.j5_deg, self.j6_deg)


@record
class ArcStart(_MotionCommand):
    """'4'/0 — first frame of an arc (G300): the intermediate point, radius and initial speed.

    H3 — arc speeds are mm/min (the vendor table's deg/s is taken for a copy slip).
    """

    NAME: ClassVar[str] = "arc start"
    CODE: ClassVar[str] = "4"
    SLOTS: ClassVar[dict[str, int]] = {
        **_POSE_SLOTS, "pwm_us": 7, **_EXTERNAL_SLOTS, "radius_mm": 10, "speed_mm_min": 11,
    }

    x_mm: float
    y_mm: float
    z_mm: float
    b0_deg: float
    b1_deg: float
    w_deg: float
    pwm_us: float
    radius_mm: float
    speed_mm_min: float
    e0_deg: float = 0.0
    e1_deg: float = 0.0

    def _validate(self) -> None:
        _check_pwm(self)
        _check_positive(self, "radius_mm")
        _check_positive(self, "speed_mm_min")

    def subcommand(self) -> int:
        return 0

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        return {}


@record
class ArcEnd(_MotionCommand):
    """'4'/1 — second frame of an arc (G301): the end point and end speed (mm/min, H3)."""

    NAME: ClassVar[str] = "arc end"
    CODE: ClassVar[str] = "4"
    SLOTS: ClassVar[dict[str, int]] = {**_POSE_SLOTS, "pwm_us": 7, **_EXTERNAL_SLOTS, "speed_mm_min": 11}

    x_mm: float
    y_mm: float
    z_mm: float
    b0_deg: float
    b1_deg: float
    w_deg: float
    pwm_us: float
    speed_mm_min: float
    e0_deg: float = 0.0
    e1_deg: float = 0.0

    def _validate(self) -> None:
        _check_pwm(self)
        _check_not_negative(self, "speed_mm_min")

    def subcommand(self) -> int:
        return 1


@record
class Delay(_MotionCommand):
    """'6' — wait ``delay_ms`` milliseconds (G4 P…). There is no command '5'."""

    NAME: ClassVar[str] = "delay"
    CODE: ClassVar[str] = "6"
    SLOTS: ClassVar[dict[str, int]] = {"delay_ms": 1}

    delay_ms: float

    def _validate(self) -> None:
        _check_not_negative(self, "delay_ms")


# from_fields' field order of each motion command (the dataclass fields exist only once @dataclass ran)
for _cls in (LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay):
    _cls._FIELD_NAMES = tuple(f.name for f in fields(_cls))


@record
class MCode(Command):
    """'7' — an M code; the number goes verbatim into a[3..6] (H4: int32 little-endian)."""

    NAME: ClassVar[str] = "M code"
    CODE: ClassVar[str] = "7"

    number: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "number", _int("MCode", "number", self.number, -(2**31), 2**31 - 1))

    def encode(self) -> bytes:
        frame = bytearray(FRAME_SIZE)
        frame[0], frame[1], frame[47] = MOTION_HEAD, ord(self.CODE), MOTION_TAIL
        M_CODE_CODEC.pack_into(frame, 3, self.number)
        return bytes(frame)

    @classmethod
    def _from_frame(cls, frame: bytes) -> "MCode":
        return cls(M_CODE_CODEC.unpack_from(frame, 3)[0])


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
            object.__setattr__(self, name, _f32("SetWorktableOrigin", name, getattr(self, name)))

    def _argument_bytes(self) -> bytes:
        return b"".join(FLOAT_CODEC.pack(v) for v in (self.x_mm, self.y_mm, self.z_mm))

    @classmethod
    def _from_frame(cls, frame: bytes) -> "SetWorktableOrigin":
        return cls(*(FLOAT_CODEC.unpack_from(frame, _slot_offset(k))[0] for k in (1, 2, 3)))


@record
class RunProgram(_ControlCommand):
    """Control 30/2 — run an SD-card program: 0 the taught one, 1…15 Route_a…Route_o (PROGRAM n)."""

    NAME: ClassVar[str] = "run SD program"
    A1: ClassVar[int] = 30
    A2: ClassVar[int] = 2

    program: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "program", _int("RunProgram", "program", self.program, *PROGRAM_RANGE))

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
        object.__setattr__(self, "pose", _int("GoToPose", "pose", self.pose, *FIXED_POSE_RANGE))

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
        axis = _int("Joystick", "axis", self.axis, 0, JOYSTICK_LINEAR_AXIS)
        if axis not in JOYSTICK_JOINT_AXES and axis != JOYSTICK_LINEAR_AXIS:
            raise FieldError(f"Joystick.axis = {axis} is neither a joint (0…5) nor linear (100)")
        values = tuple(self.values) if isinstance(self.values, (tuple, list)) else (self.values,)
        wanted = 3 if axis == JOYSTICK_LINEAR_AXIS else 1
        if len(values) != wanted:
            raise FieldError(f"Joystick axis {axis} takes {wanted} value(s), not {len(values)}")
        values = tuple(_int("Joystick", "values", v, 0, 255) for v in values)
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
        object.__setattr__(self, "mode", _int("StructureMode", "mode", self.mode, 0, 1))

    def _argument_bytes(self) -> bytes:
        return bytes([STRUCTURE_MODE_ARGUMENT[self.mode]])

    @classmethod
    def _from_frame(cls, frame: bytes) -> "StructureMode":
        for mode, argument in STRUCTURE_MODE_ARGUMENT.items():
            if frame[3] == argument:
                return cls(mode)
        raise FrameError(f"structure mode argument is {frame[3]}, expected 0 or 9")


AnyCommand = Union[
    LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay, MCode, ResetArm, ResetConnector,
    SetWorktableOrigin, RunProgram, PauseToggle, GoToPose, Joystick, StructureMode,
]

MOTION_COMMANDS = (LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay, MCode)
CONTROL_COMMANDS = (
    ResetArm, ResetConnector, SetWorktableOrigin, RunProgram, PauseToggle, GoToPose, Joystick, StructureMode,
)
_CONTROL_BY_CODE = {(c.A1, c.A2): c for c in CONTROL_COMMANDS}


def decode_command(frame: bytes) -> AnyCommand:
    """The command a 48-byte frame carries; raises FrameError or FieldError if it carries none."""
    frame = bytes(frame)
    if len(frame) != FRAME_SIZE:
        raise FrameError(f"a command frame is {FRAME_SIZE} bytes, not {len(frame)}")
    head, tail = frame[0], frame[-1]
    if head == MOTION_HEAD:
        if tail != MOTION_TAIL:
            raise FrameError(f"motion frame ends with 0x{tail:02x}, expected 0x{MOTION_TAIL:02x}")
        return _decode_motion(frame)
    if head == CONTROL_HEAD:
        if tail != CONTROL_TAIL:
            raise FrameError(f"control frame ends with 0x{tail:02x}, expected 0x{CONTROL_TAIL:02x}")
        kind = _CONTROL_BY_CODE.get((frame[1], frame[2]))
        if kind is None:
            raise FrameError(f"unknown control command {frame[1]}/{frame[2]}")
        return kind._from_frame(frame)
    raise FrameError(f"0x{head:02x} is not a frame head (0x{MOTION_HEAD:02x} or 0x{CONTROL_HEAD:02x})")


def _decode_motion(frame: bytes) -> AnyCommand:
    code = chr(frame[1])
    if code == "4":
        if frame[2] not in (0, 1):
            raise FrameError(f"arc sub-command {frame[2]} is neither 0 (G300) nor 1 (G301)")
        return (ArcStart if frame[2] == 0 else ArcEnd)._from_frame(frame)
    for kind in (LinearMove, AccelLinearMove, JointMove, Delay, MCode):
        if kind.CODE == code:
            return kind._from_frame(frame)
    raise FrameError(f"unknown motion command 0x{frame[1]:02x}")


# --- status frames, byte streams, readable form: armctl/status_frames.py -----------------------


def __getattr__(name: str):
    """``StatusFrame``, ``decode_status``, ``StatusReader``, ``scan_frames``, ``describe`` … live
    in armctl/status_frames.py, imported on first use (a command that never reads the arm does
    not build them at every start); they are part of this module's interface all the same."""
    if name.startswith("__"):  # the import system asks for __path__ at every "from armctl.protocol import …"
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from . import status_frames

    try:
        return getattr(status_frames, name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
