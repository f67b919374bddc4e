"""Arm → host status frames, frames found in any byte stream, and every frame's readable form.

Strategy: the part of armctl/core/protocol.py that a command which never reads the arm (compile,
lint, estimate) does not need, kept apart so that such a command does not build its fourteen
frozen dataclasses at every start (issue 13: start-up).  ``armctl.core.protocol`` still offers
every name defined here (its module ``__getattr__`` imports this module on first use; the
import system's lock defines the classes once even when two threads ask at once), so callers
import from either.  This module imports the protocol's parts below the façade (the wire's
numbers and field checks from armctl/core/frame_fields.py, ``decode_command`` from
armctl/core/commands.py), never the façade itself: no cycle.  The rules are protocol.py's: bytes
and nothing else, no I/O.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, fields
from typing import ClassVar, Iterator

from ..errors import FieldError, FrameError
from .commands import AnyCommand, decode_command
from .frame_fields import (
    CONTROL_HEAD, CONTROL_TAIL, FLOAT_CODEC, FRAME_SIZE, MOTION_HEAD, MOTION_TAIL, STATUS_HEAD, STATUS_SIZE, STATUS_TAIL,
    STATUS_WORD_CODEC, Command, f32_field, f32_repr, int_field,
)

# --- arm → host status frames -----------------------------------------------------------------


@dataclass(frozen=True)
class StatusFrame:
    """Base of the 9 status kinds: ``0xCE d0..d5 kind 0xCF``."""

    KIND: ClassVar[int] = -1
    NAME: ClassVar[str] = ""

    def encode(self) -> bytes:
        frame = bytearray(STATUS_SIZE)
        frame[0], frame[7], frame[8] = STATUS_HEAD, self.KIND, STATUS_TAIL
        frame[1:7] = self._data().ljust(6, b"\0")
        return bytes(frame)

    def _data(self) -> bytes:  # pragma: no cover - every subclass overrides
        raise NotImplementedError

    def fields(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _word(cls_name: str, name: str, value, scale: int) -> float:
    """A value carried as a signed 16-bit word of ``value × scale``, normalised to that grid."""
    return _raw_word(cls_name, name, value, scale) / scale


def _raw_word(cls_name: str, name: str, value, scale: int) -> int:
    """The signed 16-bit word carrying ``value × scale``; FieldError if it does not fit."""
    scaled = _f64(cls_name, name, value) * scale
    # a huge finite value overflows to infinity once scaled: it does not fit either
    raw = round(scaled) if math.isfinite(scaled) else None
    if raw is None or not -32768 <= raw <= 32767:
        raise FieldError(f"{cls_name}.{name} = {value} does not fit a 16-bit status word at ×{scale}")
    return raw


def _f64(cls_name: str, name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FieldError(f"{cls_name}.{name} must be a finite number, not {value!r}")
    return float(value)


def _words(values, scale: int) -> bytes:
    return b"".join(STATUS_WORD_CODEC.pack(round(v * scale)) for v in values)


def _unwords(data: bytes, count: int, scale: int) -> list[float]:
    return [STATUS_WORD_CODEC.unpack_from(data, 2 * k)[0] / scale for k in range(count)]


_STATUS_HEAD_BYTE = bytes((STATUS_HEAD,))


def _as_read(cls, **values) -> "StatusFrame":
    """A frame of ``cls`` holding ``values`` read off the wire, which are what its checks would
    give by construction: set past the frozen ``__setattr__`` and the checks (one frame per 30 ms)."""
    frame = object.__new__(cls)
    frame.__dict__.update(values)
    return frame

MM_SCALE = 10  # status lengths are 0.1 mm
DEG_SCALE = 100  # status angles are 0.01 deg (H8: kinds 3 and 5 reuse kinds 0 and 1's scales)


@dataclass(frozen=True)
class ThreeWordStatus(StatusFrame):
    SCALE: ClassVar[int] = 1

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, _word(type(self).__name__, f.name, getattr(self, f.name), self.SCALE))

    def _data(self) -> bytes:
        return _words(self.fields().values(), self.SCALE)

    @classmethod
    def _field_names(cls) -> tuple[str, ...]:
        names = cls.__dict__.get("_names")
        if names is None:
            names = tuple(f.name for f in fields(cls))
            type.__setattr__(cls, "_names", names)
            # the frame's bytes after the head: its words, zeros to six data bytes, kind, tail
            codec = struct.Struct(STATUS_WORD_CODEC.format[0] + "h" * len(names) + f"{6 - 2 * len(names)}xBB")
            type.__setattr__(cls, "_codec", codec)
            type.__setattr__(cls, "_unpack_words", struct.Struct(STATUS_WORD_CODEC.format[0] + "h" * len(names)).unpack_from)
        return names

    @classmethod
    def encode_values(cls, *values) -> bytes:
        """``cls(*values).encode()``, the same bytes and the same FieldError, without building
        the frame: the simulator sends one per 30 ms (40,000 in 20 minutes).  A value stored
        as ``raw / SCALE`` packs back to ``raw`` (the product is within an ulp of an integer
        far below 2**52), so the word is the one ``encode`` packs."""
        names, scale, name = cls._field_names(), cls.SCALE, cls.__name__
        if len(values) != len(names):
            raise TypeError(f"{name} takes {len(names)} values, not {len(values)}")
        words = [_raw_word(name, f, v, scale) for f, v in zip(names, values)]
        return _STATUS_HEAD_BYTE + cls._codec.pack(*words, cls.KIND, STATUS_TAIL)

    @classmethod
    def _from_data(cls, data: bytes) -> "StatusFrame":
        return cls._decoder()(data, 0)

    @classmethod
    def _decoder(cls):
        """The frame of ``cls`` whose words begin at ``offset`` of ``data``, as a function of
        (data, offset), made once per class: words read off the wire are on the grid and in range
        by construction, so they are set as they are (the same values __post_init__ would give:
        _unwords' word ÷ scale, all words in one unpack), past the frozen __setattr__ and without
        checking each again — every status frame read, 40,000 in 20 minutes (``_from_data``, and
        ``StatusReader.decode_frame`` on a whole frame)."""
        decode = cls.__dict__.get("_decode")
        if decode is not None:
            return decode
        names, scale, new = cls._field_names(), cls.SCALE, object.__new__
        unpack, first, second = cls._unpack_words, names[0], names[1]
        if len(names) == 3:
            third = names[2]

            def decode(data, offset):
                a, b, c = unpack(data, offset)
                frame = new(cls)
                values = frame.__dict__
                values[first], values[second], values[third] = a / scale, b / scale, c / scale
                return frame
        else:
            def decode(data, offset):
                a, b = unpack(data, offset)
                frame = new(cls)
                values = frame.__dict__
                values[first], values[second] = a / scale, b / scale
                return frame
        type.__setattr__(cls, "_decode", decode)
        return decode


@dataclass(frozen=True)
class PositionStatus(ThreeWordStatus):
    """Kind 0 — tool position X, Y, Z in mm."""

    KIND: ClassVar[int] = 0
    NAME: ClassVar[str] = "position"
    SCALE: ClassVar[int] = MM_SCALE
    x_mm: float
    y_mm: float
    z_mm: float


@dataclass(frozen=True)
class JointsLowStatus(ThreeWordStatus):
    """Kind 1 — joints 1, 2, 3 (a0, a1, a2) in degrees."""

    KIND: ClassVar[int] = 1
    NAME: ClassVar[str] = "joints 1-3"
    SCALE: ClassVar[int] = DEG_SCALE
    j1_deg: float
    j2_deg: float
    j3_deg: float


@dataclass(frozen=True)
class JointsHighStatus(ThreeWordStatus):
    """Kind 2 — joints 4, 5, 6 (b0/w0, b1/w1, aw) in degrees."""

    KIND: ClassVar[int] = 2
    NAME: ClassVar[str] = "joints 4-6"
    SCALE: ClassVar[int] = DEG_SCALE
    j4_deg: float
    j5_deg: float
    j6_deg: float


@dataclass(frozen=True)
class WorktableStatus(ThreeWordStatus):
    """Kind 3 — worktable origin X0, Y0, Z0 in mm."""

    KIND: ClassVar[int] = 3
    NAME: ClassVar[str] = "worktable origin"
    SCALE: ClassVar[int] = MM_SCALE
    x_mm: float
    y_mm: float
    z_mm: float


@dataclass(frozen=True)
class WristStatus(ThreeWordStatus):
    """Kind 5 — w0, w1 in degrees; d4..d5 unused."""

    KIND: ClassVar[int] = 5
    NAME: ClassVar[str] = "wrist"
    SCALE: ClassVar[int] = DEG_SCALE
    w0_deg: float
    w1_deg: float


@dataclass(frozen=True)
class PauseStatus(StatusFrame):
    """Kind 4 — d1 = pause state (raw byte, non-zero = paused); d4..d5 = PWM in µs."""

    KIND: ClassVar[int] = 4
    NAME: ClassVar[str] = "pause and PWM"
    pause_state: int
    pwm_us: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "pause_state", int_field("PauseStatus", "pause_state", self.pause_state, 0, 255))
        object.__setattr__(self, "pwm_us", int_field("PauseStatus", "pwm_us", self.pwm_us, -32768, 32767))

    @property
    def paused(self) -> bool:
        return self.pause_state != 0

    def _data(self) -> bytes:
        return bytes([0, self.pause_state, 0, 0]) + STATUS_WORD_CODEC.pack(self.pwm_us)

    @classmethod
    def _from_data(cls, data: bytes) -> "PauseStatus":
        # a byte and a signed word off the wire are in range by construction (what
        # __post_init__ checks): set as read, every status frame read (as ThreeWordStatus does)
        return _as_read(cls, pause_state=data[1], pwm_us=STATUS_WORD_CODEC.unpack_from(data, 4)[0])


@dataclass(frozen=True)
class _FloatStatus(StatusFrame):
    value: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", f32_field(type(self).__name__, "value", self.value))

    def _data(self) -> bytes:
        return FLOAT_CODEC.pack(self.value)

    @classmethod
    def _from_data(cls, data: bytes) -> "StatusFrame":
        value = FLOAT_CODEC.unpack_from(data, 0)[0]
        if not math.isfinite(value):
            raise FieldError(f"{cls.NAME} carries {f32_repr(value)}, not a finite number")
        return _as_read(cls, value=value)  # a finite float32 already: what f32_field would give


@dataclass(frozen=True)
class FileLengthStatus(_FloatStatus):
    """Kind 100 — SD program file length (float, H8: little-endian)."""

    KIND: ClassVar[int] = 100
    NAME: ClassVar[str] = "SD file length"


@dataclass(frozen=True)
class RunPositionStatus(_FloatStatus):
    """Kind 103 — SD program run position (float, H8: little-endian)."""

    KIND: ClassVar[int] = 103
    NAME: ClassVar[str] = "SD run position"


@dataclass(frozen=True)
class FileStatus(StatusFrame):
    """Kind 102 — SD program file status, d0..d1 as a raw big-endian 16-bit number."""

    KIND: ClassVar[int] = 102
    NAME: ClassVar[str] = "SD file status"
    raw: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "raw", int_field("FileStatus", "raw", self.raw, 0, 0xFFFF))

    def _data(self) -> bytes:
        return self.raw.to_bytes(2, "big")

    @classmethod
    def _from_data(cls, data: bytes) -> "FileStatus":
        return _as_read(cls, raw=int.from_bytes(data[0:2], "big"))  # 0…0xFFFF by construction


STATUS_KINDS: dict[int, type[StatusFrame]] = {
    k.KIND: k
    for k in (
        PositionStatus, JointsLowStatus, JointsHighStatus, WorktableStatus, PauseStatus, WristStatus,
        FileLengthStatus, FileStatus, RunPositionStatus,
    )
}
# The order in which the arm rotates through the kinds, one every STATUS_PERIOD_S.
STATUS_ROTATION = (0, 1, 2, 3, 4, 5, 100, 102, 103)


def is_status_frame(data: bytes, offset: int = 0) -> bool:
    """H9 — a status frame is recognised by 0xCE … 0xCF around a known kind byte; nothing else."""
    return (
        len(data) - offset >= STATUS_SIZE
        and data[offset] == STATUS_HEAD
        and data[offset + 8] == STATUS_TAIL
        and data[offset + 7] in STATUS_KINDS
    )


def decode_status(frame: bytes) -> StatusFrame:
    """The status a 9-byte frame carries; raises FrameError if it is not one."""
    frame = bytes(frame)
    if len(frame) != STATUS_SIZE:
        raise FrameError(f"a status frame is {STATUS_SIZE} bytes, not {len(frame)}")
    if not is_status_frame(frame):
        raise FrameError(f"not a status frame: {frame.hex(' ')}")
    return STATUS_KINDS[frame[7]]._from_data(frame[1:7])


# --- finding frames in any byte stream (armctl decode) ----------------------------------------


@dataclass(frozen=True)
class Chunk:
    """A run of bytes at ``offset``: a frame (``frame`` set), a framed but invalid command
    (``error`` set), or bytes that belong to no frame (both None)."""

    offset: int
    data: bytes
    frame: AnyCommand | StatusFrame | None = None
    error: str | None = None


def scan_frames(data: bytes) -> Iterator[Chunk]:
    """Split bytes holding command and status frames in any mix into chunks, in order."""
    data = bytes(data)
    position, junk_start = 0, 0

    def junk_until(end: int) -> Iterator[Chunk]:
        if end > junk_start:
            yield Chunk(junk_start, data[junk_start:end])

    while position < len(data):
        chunk = chunk_at(data, position)
        if chunk is None:
            position += 1
            continue
        yield from junk_until(position)
        yield chunk
        position += len(chunk.data)
        junk_start = position
    yield from junk_until(len(data))


def chunk_at(data: bytes, position: int) -> Chunk | None:
    """The frame that starts at ``position`` of ``data`` (a Chunk), or None when none does: what
    ``scan_frames`` and decode's block-by-block ``FrameScanner`` both decide at a head byte."""
    head = data[position]
    if head in (MOTION_HEAD, CONTROL_HEAD) and len(data) - position >= FRAME_SIZE:
        frame = data[position : position + FRAME_SIZE]
        if frame[-1] == (MOTION_TAIL if head == MOTION_HEAD else CONTROL_TAIL):
            try:
                return Chunk(position, frame, decode_command(frame))
            except FieldError as error:
                return Chunk(position, frame, None, str(error))
            except FrameError:
                pass
    if is_status_frame(data, position):
        frame = data[position : position + STATUS_SIZE]
        try:
            return Chunk(position, frame, decode_status(frame))
        except FieldError as error:  # well framed, impossible value (an inf or NaN float)
            return Chunk(position, frame, None, str(error))
        except FrameError:
            return None
    return None


# --- readable form (armctl decode, logs) ------------------------------------------------------

_UNIT_SUFFIXES = (
    ("_mm_min", "mm/min"), ("_deg_s", "deg/s"), ("_mm_s2", "mm/s²"), ("_mm", "mm"), ("_deg", "deg"),
    ("_us", "µs"), ("_ms", "ms"),
)


def describe(frame: Command | StatusFrame) -> str:
    """One readable line: the frame's name and each field with its unit."""
    parts = []
    for name, value in frame.fields().items():
        label, unit = name, ""
        for suffix, suffix_unit in _UNIT_SUFFIXES:
            if name.endswith(suffix):
                label, unit = name[: -len(suffix)], " " + suffix_unit
                break
        if isinstance(value, float):
            text = f32_repr(value)
        elif isinstance(value, tuple):
            text = ",".join(str(v) for v in value)
        else:
            text = str(value)
        parts.append(f"{label}={text}{unit}")
    return " ".join([frame.NAME, *parts])
