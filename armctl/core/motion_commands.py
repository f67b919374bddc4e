"""The seven motion commands (0xEE … 0xEF frames): their fields, checks and exact bytes.

Strategy: each command is a frozen ``record`` whose float fields are rounded to single
precision on construction (one pack/unpack for all of them, ``_MotionCommand.__post_init__``),
so an object holds exactly what the wire will, and ``encode`` is one ``struct`` pack of the
whole frame.  A compiler builds one per line: ``from_fields`` is straight-line code compiled
once per class for the common all-float case, the same object and the same checks as
``cls(*values)``.  The field checks and numbers come from armctl/core/frame_fields.py;
armctl/core/protocol.py is the façade that offers every name.  Bytes only, no I/O.
"""

from __future__ import annotations

import math
import operator
import struct
from dataclasses import fields
from typing import ClassVar

from ..errors import FieldError, FrameError
from .frame_fields import (
    FRAME_SIZE, LINEAR_SUBCOMMAND_FOR_CHANNEL_1, M_CODE_CODEC, MOTION_HEAD, MOTION_TAIL, PWM_RANGE_US,
    SMOOTHING_RANGE, ACCEL_RANGE_MM_S2, Command, check_range, f32_field, f32_repr, int_field,
)
from .records import record

_PLAIN_NUMBERS = frozenset((int, float))  # exact types: bool is refused, as f32_field does


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
        cls._SLOT_NAMES = tuple(by_slot[k] for k in sorted(by_slot))  # _FRAME_CODEC's floats, in order

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
                object.__setattr__(self, name, f32_field(type(self).__name__, name, getattr(self, name)))
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
        # the slots in one unpack (``_FRAME_CODEC``: head, code, sub-command, the named slots in
        # slot order, tail), the command built as ``from_fields`` builds it: ``cls(**values)``,
        # the same checks (the simulated arm decodes every frame it is sent)
        values = dict(zip(cls._SLOT_NAMES, cls._FRAME_CODEC.unpack_from(frame)[3:-1]))
        values.update(cls._ints_from_subcommand(frame[2]))
        names = cls._FIELD_NAMES
        if len(values) == len(names):
            try:
                arguments = [values[name] for name in names]
            except KeyError:  # (a field the frame does not hold: its default, from the keywords)
                return cls(**values)
            return cls.from_fields(*arguments)
        return cls(**values)

    @classmethod
    def _ints_from_subcommand(cls, subcommand: int) -> dict:
        return {}


_POSE_SLOTS = {"x_mm": 1, "y_mm": 2, "z_mm": 3, "b0_deg": 4, "b1_deg": 5, "w_deg": 6}
_EXTERNAL_SLOTS = {"e0_deg": 8, "e1_deg": 9}


def _check_pwm(obj) -> None:
    check_range(type(obj).__name__, "pwm_us", obj.pwm_us, *PWM_RANGE_US)


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
            object.__setattr__(self, "pwm_channel", int_field("LinearMove", "pwm_channel", channel, 1, 4))
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
        object.__setattr__(self, "mode", int_field("AccelLinearMove", "mode", self.mode, 0, 2))
        check_range("AccelLinearMove", "accel_mm_s2", self.accel_mm_s2, *ACCEL_RANGE_MM_S2)
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
        object.__setattr__(self, "smoothing", int_field("JointMove", "smoothing", self.smoothing, *SMOOTHING_RANGE))
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
        object.__setattr__(self, "number", int_field("MCode", "number", self.number, -(2**31), 2**31 - 1))

    def encode(self) -> bytes:
        frame = bytearray(FRAME_SIZE)
        frame[0], frame[1], frame[47] = MOTION_HEAD, ord(self.CODE), MOTION_TAIL
        M_CODE_CODEC.pack_into(frame, 3, self.number)
        return bytes(frame)

    @classmethod
    def _from_frame(cls, frame: bytes) -> "MCode":
        return cls(M_CODE_CODEC.unpack_from(frame, 3)[0])
