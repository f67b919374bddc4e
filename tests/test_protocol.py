"""The frame codec against PROTOCOL.md.

Strategy: the golden vectors in tests/data were written by hand from PROTOCOL.md's byte
tables (never produced by the encoder); each is checked in both directions.  Then the error
cases the spec implies, then Hypothesis: every valid object survives encode → decode exactly,
and arbitrary 48-byte frames either decode to something that re-encodes to the same
meaningful bytes or raise FrameError/FieldError — nothing else.
"""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from armctl.errors import ArmctlError, FieldError, FrameError
from armctl.core.protocol import (
    CONTROL_COMMANDS,
    MOTION_COMMANDS,
    STATUS_KINDS,
    AccelLinearMove,
    ArcEnd,
    ArcStart,
    Delay,
    FileLengthStatus,
    FileStatus,
    GoToPose,
    JointMove,
    JointsHighStatus,
    JointsLowStatus,
    Joystick,
    LinearMove,
    MCode,
    PauseStatus,
    PauseToggle,
    PositionStatus,
    ResetArm,
    ResetConnector,
    RunPositionStatus,
    RunProgram,
    SetWorktableOrigin,
    StatusFrame,
    StructureMode,
    WorktableStatus,
    WristStatus,
    decode_command,
    decode_status,
    describe,
)

FAST = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
F32_MAX = struct.unpack("<f", bytes.fromhex("ffff7f7f"))[0]  # largest finite float32


def hex_diff(actual: bytes, expected: bytes) -> str:
    """Where two frames differ, byte by byte, for a readable failure."""
    if len(actual) != len(expected):
        return f"length {len(actual)} != {len(expected)}"
    return ", ".join(f"a[{i}]: {a:02x} != {e:02x}" for i, (a, e) in enumerate(zip(actual, expected)) if a != e)


def f32(value: float) -> float:
    """``value`` rounded to IEEE single precision, computed here without armctl."""
    return struct.unpack("<f", struct.pack("<f", value))[0]


# --- golden vectors, both ways -----------------------------------------------------------------


def test_golden_commands_cover_all_fifteen_commands(all_command_vectors):
    classes = {type(v.obj) for v in all_command_vectors}
    assert classes == set(MOTION_COMMANDS) | set(CONTROL_COMMANDS)
    assert len(classes) == 15


def test_golden_status_covers_all_nine_kinds(all_status_vectors):
    assert sorted(type(v.obj).KIND for v in all_status_vectors) == [0, 1, 2, 3, 4, 5, 100, 102, 103]
    assert {type(v.obj) for v in all_status_vectors} == set(STATUS_KINDS.values())


def test_command_encodes_to_golden_bytes(command_vector):
    if command_vector.decode_only:
        pytest.skip("one-way vector: bytes → object only")
    actual = command_vector.obj.encode()
    assert actual == command_vector.data, hex_diff(actual, command_vector.data)


def test_golden_bytes_decode_to_command(command_vector):
    decoded = decode_command(command_vector.data)
    assert type(decoded) is type(command_vector.obj)
    assert decoded == command_vector.obj
    assert decode_command(bytearray(command_vector.data)) == command_vector.obj  # any bytes-like


def test_status_encodes_to_golden_bytes(status_vector):
    actual = status_vector.obj.encode()
    assert actual == status_vector.data, hex_diff(actual, status_vector.data)


def test_golden_bytes_decode_to_status(status_vector):
    decoded = decode_status(status_vector.data)
    assert type(decoded) is type(status_vector.obj)
    assert decoded == status_vector.obj


def test_linear_move_subcommand_0_means_channel_1_and_is_sent_as_1(all_command_vectors):
    """PROTOCOL.md: a[2] = 0 or 1 both drive PWM channel 1; armctl sends 1."""
    by_name = {v.name: v for v in all_command_vectors}
    zero, one = by_name["linear_move_subcommand_0"], by_name["linear_move_channel_1"]
    assert zero.data[2] == 0 and one.data[2] == 1 and zero.data[3:] == one.data[3:]
    decoded = decode_command(zero.data)
    assert decoded.pwm_channel == 1
    assert decoded.encode() == one.data


def test_describe_names_the_frame_and_carries_units(command_vector):
    text = describe(command_vector.obj)
    assert text.startswith(type(command_vector.obj).NAME)


def test_describe_examples():
    assert describe(Delay(delay_ms=250)) == "delay delay=250 ms"
    assert describe(PositionStatus(x_mm=100.0, y_mm=-0.1, z_mm=0.0)) == "position x=100 mm y=-0.1 mm z=0 mm"


# --- normalisation on construction ------------------------------------------------------------


def test_floats_are_normalised_to_float32_on_construction():
    origin = SetWorktableOrigin(x_mm=0.1, y_mm=1e-50, z_mm=-0.0)
    assert origin.x_mm == 0.10000000149011612  # float32 nearest to 0.1
    assert origin.y_mm == 0.0  # underflows in single precision
    assert origin == SetWorktableOrigin(x_mm=f32(0.1), y_mm=0.0, z_mm=0.0)


def test_status_values_are_normalised_to_their_wire_resolution():
    assert PositionStatus(x_mm=0.04, y_mm=0.06, z_mm=-0.26).fields() == {"x_mm": 0.0, "y_mm": 0.1, "z_mm": -0.3}
    assert JointsLowStatus(j1_deg=0.123, j2_deg=0, j3_deg=0).j1_deg == 0.12


def test_integral_float_is_accepted_for_an_integer_field():
    assert RunProgram(program=2.0) == RunProgram(program=2)


def test_largest_float32_is_accepted():
    assert SetWorktableOrigin(x_mm=F32_MAX, y_mm=-F32_MAX, z_mm=0).encode()[3:11].hex() == "ffff7f7fffff7fff"


def test_range_boundaries_are_accepted():
    LinearMove(0, 0, 0, 0, 0, 0, pwm_us=500, speed_mm_min=1, pwm_channel=4)
    LinearMove(0, 0, 0, 0, 0, 0, pwm_us=2500, speed_mm_min=1, pwm_channel=1)
    AccelLinearMove(0, 0, 0, 0, 0, 0, 0, accel_mm_s2=-3200, speed1_mm_min=1)
    AccelLinearMove(2, 0, 0, 0, 0, 0, 0, accel_mm_s2=3200, speed1_mm_min=1, speed0_mm_min=1)
    JointMove(0, 0, 0, 0, 0, 0, pwm_us=500, speed_deg_s=1, smoothing=0)
    JointMove(0, 0, 0, 0, 0, 0, pwm_us=2500, speed_deg_s=1, smoothing=6)
    RunProgram(0), RunProgram(15), GoToPose(0), GoToPose(3)
    Joystick(0, (0,)), Joystick(5, (255,)), Joystick(100, (0, 128, 255))
    MCode(-(2**31)), MCode(2**31 - 1)


# --- errors: fields that cannot be constructed -----------------------------------------------

_POSE = dict(x_mm=0, y_mm=0, z_mm=0, b0_deg=0, b1_deg=0, w_deg=0)
VALID = {
    LinearMove: dict(_POSE, pwm_us=1500, speed_mm_min=1000),
    AccelLinearMove: dict(_POSE, mode=1, accel_mm_s2=100, speed1_mm_min=1000),
    JointMove: dict(j1_deg=0, j2_deg=0, j3_deg=0, j4_deg=0, j5_deg=0, j6_deg=0, pwm_us=1500, speed_deg_s=10),
    ArcStart: dict(_POSE, pwm_us=1500, radius_mm=10, speed_mm_min=1000),
    ArcEnd: dict(_POSE, pwm_us=1500, speed_mm_min=1000),
    Delay: dict(delay_ms=10),
    MCode: dict(number=3),
    SetWorktableOrigin: dict(x_mm=0, y_mm=0, z_mm=0),
    RunProgram: dict(program=0),
    GoToPose: dict(pose=0),
    Joystick: dict(axis=0, values=(128,)),
    StructureMode: dict(mode=0),
    PositionStatus: dict(x_mm=0, y_mm=0, z_mm=0),
    JointsLowStatus: dict(j1_deg=0, j2_deg=0, j3_deg=0),
    WristStatus: dict(w0_deg=0, w1_deg=0),
    PauseStatus: dict(pause_state=0, pwm_us=1500),
    FileStatus: dict(raw=0),
    FileLengthStatus: dict(value=0),
}


def test_valid_baselines_construct():
    for cls, kwargs in VALID.items():
        cls(**kwargs)


# (class, field overrides, regex the message must match)
BAD_FIELDS = [
    # PWM 500…2500 µs
    (LinearMove, dict(pwm_us=499.5), r"LinearMove\.pwm_us = 499\.5 is outside 500…2500"),
    (LinearMove, dict(pwm_us=2500.5), r"LinearMove\.pwm_us = 2500\.5 is outside"),
    (LinearMove, dict(pwm_us=0), r"LinearMove\.pwm_us = 0 is outside"),
    (JointMove, dict(pwm_us=2501), r"JointMove\.pwm_us = 2501 is outside"),
    (ArcStart, dict(pwm_us=-1500), r"ArcStart\.pwm_us = -1500 is outside"),
    (ArcEnd, dict(pwm_us=3000), r"ArcEnd\.pwm_us = 3000 is outside"),
    # acceleration −3200…3200 mm/s²
    (AccelLinearMove, dict(accel_mm_s2=3200.5), r"AccelLinearMove\.accel_mm_s2 = 3200\.5 is outside -3200…3200"),
    (AccelLinearMove, dict(accel_mm_s2=-3201), r"accel_mm_s2 = -3201 is outside"),
    (AccelLinearMove, dict(accel_mm_s2=1e6), r"accel_mm_s2 = 1000000 is outside"),
    (AccelLinearMove, dict(mode=3), r"AccelLinearMove\.mode = 3 is outside 0…2"),
    (AccelLinearMove, dict(mode=0, speed0_mm_min=100), r"speed0_mm_min is used in mode 2 only"),
    # smoothing 0…6
    (JointMove, dict(smoothing=7), r"JointMove\.smoothing = 7 is outside 0…6"),
    (JointMove, dict(smoothing=-1), r"JointMove\.smoothing = -1 is outside"),
    # SD program 0…15, fixed pose 0…3, structure mode 0/1
    (RunProgram, dict(program=16), r"RunProgram\.program = 16 is outside 0…15"),
    (RunProgram, dict(program=-1), r"RunProgram\.program = -1 is outside"),
    (GoToPose, dict(pose=4), r"GoToPose\.pose = 4 is outside 0…3"),
    (GoToPose, dict(pose=-1), r"GoToPose\.pose = -1 is outside"),
    (StructureMode, dict(mode=2), r"StructureMode\.mode = 2 is outside 0…1"),
    # PWM channel 1…4
    (LinearMove, dict(pwm_channel=0), r"LinearMove\.pwm_channel = 0 is outside 1…4"),
    (LinearMove, dict(pwm_channel=5), r"LinearMove\.pwm_channel = 5 is outside"),
    # joystick: axis 0…5 or 100, bytes 0…255, one value per joint or three for the line
    (Joystick, dict(axis=6), r"Joystick\.axis = 6 is neither a joint \(0…5\) nor linear \(100\)"),
    (Joystick, dict(axis=99), r"Joystick\.axis = 99 is neither"),
    (Joystick, dict(axis=101), r"Joystick\.axis = 101"),
    (Joystick, dict(axis=-1), r"Joystick\.axis = -1"),
    (Joystick, dict(values=(256,)), r"Joystick\.values = 256 is outside 0…255"),
    (Joystick, dict(values=(-1,)), r"Joystick\.values = -1 is outside"),
    (Joystick, dict(axis=100, values=(128, 128, 300)), r"Joystick\.values = 300"),
    (Joystick, dict(axis=100, values=(128,)), r"Joystick axis 100 takes 3 value\(s\), not 1"),
    (Joystick, dict(axis=2, values=(128, 128, 128)), r"Joystick axis 2 takes 1 value\(s\), not 3"),
    # M number: int32
    (MCode, dict(number=2**31), r"MCode\.number = 2147483648 is outside"),
    (MCode, dict(number=-(2**31) - 1), r"MCode\.number = -2147483649 is outside"),
    # non-finite
    (LinearMove, dict(x_mm=math.nan), r"LinearMove\.x_mm must be finite, not nan"),
    (LinearMove, dict(pwm_us=math.nan), r"LinearMove\.pwm_us must be finite"),
    (AccelLinearMove, dict(accel_mm_s2=math.inf), r"accel_mm_s2 must be finite, not inf"),
    (SetWorktableOrigin, dict(y_mm=-math.inf), r"SetWorktableOrigin\.y_mm must be finite, not -inf"),
    (Delay, dict(delay_ms=math.nan), r"Delay\.delay_ms must be finite"),
    (JointMove, dict(e1_deg=math.inf), r"JointMove\.e1_deg must be finite"),
    (FileLengthStatus, dict(value=math.nan), r"FileLengthStatus\.value must be finite"),
    (PositionStatus, dict(z_mm=math.inf), r"PositionStatus\.z_mm must be a finite number"),
    # too large for float32 (or for a 16-bit status word)
    (LinearMove, dict(y_mm=3.5e38), r"LinearMove\.y_mm = 3\.5e\+38 does not fit a 32-bit float"),
    (ArcStart, dict(radius_mm=1e300), r"ArcStart\.radius_mm = 1e\+300 does not fit"),
    (SetWorktableOrigin, dict(z_mm=-1e39), r"SetWorktableOrigin\.z_mm = -1e\+39 does not fit"),
    (PositionStatus, dict(x_mm=3276.8), r"PositionStatus\.x_mm = 3276\.8 does not fit a 16-bit status word"),
    (JointsLowStatus, dict(j3_deg=-327.69), r"JointsLowStatus\.j3_deg = -327\.69 does not fit"),
    (PauseStatus, dict(pause_state=256), r"PauseStatus\.pause_state = 256 is outside"),
    (FileStatus, dict(raw=65536), r"FileStatus\.raw = 65536 is outside"),
    # wrong types: bools and strings are not numbers, fractions are not whole numbers
    (LinearMove, dict(x_mm=True), r"LinearMove\.x_mm must be a number, not True"),
    (LinearMove, dict(z_mm="1"), r"LinearMove\.z_mm must be a number, not '1'"),
    (LinearMove, dict(speed_mm_min=None), r"LinearMove\.speed_mm_min must be a number, not None"),
    (LinearMove, dict(pwm_channel=True), r"LinearMove\.pwm_channel must be a whole number, not True"),
    (JointMove, dict(smoothing="3"), r"JointMove\.smoothing must be a whole number, not '3'"),
    (RunProgram, dict(program=1.5), r"RunProgram\.program must be a whole number, not 1\.5"),
    (RunProgram, dict(program=False), r"RunProgram\.program must be a whole number, not False"),
    (MCode, dict(number=True), r"MCode\.number must be a whole number"),
    (MCode, dict(number="M3"), r"MCode\.number must be a whole number"),
    (Joystick, dict(values=(True,)), r"Joystick\.values must be a whole number"),
    (Joystick, dict(axis="0"), r"Joystick\.axis must be a whole number"),
    (WristStatus, dict(w0_deg=True), r"WristStatus\.w0_deg must be a finite number, not True"),
    (FileLengthStatus, dict(value="1"), r"FileLengthStatus\.value must be a number"),
]


@pytest.mark.parametrize(
    "cls, overrides, message",
    BAD_FIELDS,
    ids=[f"{cls.__name__}-{'-'.join(f'{k}={v!r}' for k, v in o.items())}" for cls, o, _ in BAD_FIELDS],
)
def test_bad_field_raises_field_error(cls, overrides, message):
    with pytest.raises(FieldError, match=message):
        cls(**{**VALID[cls], **overrides})


# --- errors: bytes that are not a command frame ----------------------------------------------


def _frame(*head: int, tail: int, **at: int) -> bytes:
    """48 bytes: ``head`` from a[0], ``tail`` at a[47], zeros elsewhere except ``a<i>=value``."""
    frame = bytearray(48)
    frame[: len(head)] = bytes(head)
    frame[47] = tail
    for key, value in at.items():
        frame[int(key[1:])] = value
    return bytes(frame)


_LINEAR = LinearMove(**VALID[LinearMove]).encode()


@pytest.mark.parametrize("length", [0, 1, 9, 47, 49, 96])
def test_decode_command_rejects_wrong_length(length):
    data = (_LINEAR * 2)[:length]
    with pytest.raises(FrameError, match=f"a command frame is 48 bytes, not {length}"):
        decode_command(data)


@pytest.mark.parametrize("head", [0x00, 0xCE, 0xED, 0xEF, 0xFB, 0xFD, 0xFF])
def test_decode_command_rejects_wrong_head(head):
    with pytest.raises(FrameError, match=f"0x{head:02x} is not a frame head"):
        decode_command(bytes([head]) + _LINEAR[1:])


@pytest.mark.parametrize(
    "frame, tail",
    [
        (_LINEAR[:47] + b"\xfd", "fd"),  # motion head, control tail
        (_LINEAR[:47] + b"\x00", "00"),
        (_LINEAR[:47] + b"\xee", "ee"),
        (ResetArm().encode()[:47] + b"\xef", "ef"),  # control head, motion tail
        (ResetArm().encode()[:47] + b"\x00", "00"),
    ],
    ids=["motion-fd", "motion-00", "motion-ee", "control-ef", "control-00"],
)
def test_decode_command_rejects_wrong_tail(frame, tail):
    with pytest.raises(FrameError, match=f"ends with 0x{tail}"):
        decode_command(frame)


# '5' does not exist; a[1] is an ASCII character, so a binary 1 is not the linear move.
@pytest.mark.parametrize("code", [ord("5"), ord("0"), ord("8"), ord("A"), 0x00, 0x01, 0x02, 0x07, 0xFF])
def test_decode_command_rejects_unknown_motion_code(code):
    with pytest.raises(FrameError, match=f"unknown motion command 0x{code:02x}"):
        decode_command(_LINEAR[:1] + bytes([code]) + _LINEAR[2:])


@pytest.mark.parametrize("a1, a2", [(12, 0), (12, 4), (12, 1), (20, 0), (20, 2), (30, 1), (30, 4), (30, 8), (0, 0), (255, 255), (3, 12)])
def test_decode_command_rejects_unknown_control_pair(a1, a2):
    with pytest.raises(FrameError, match=f"unknown control command {a1}/{a2}"):
        decode_command(_frame(0xFC, a1, a2, tail=0xFD))


@pytest.mark.parametrize(
    "frame, message",
    [
        (_frame(0xEE, ord("4"), 2, tail=0xEF), r"arc sub-command 2"),
        (_LINEAR[:2] + b"\x05" + _LINEAR[3:], r"linear move sub-command 5"),
        (_frame(0xFC, 30, 3, 0, tail=0xFD), r"pause frame argument is 0"),
        (_frame(0xFC, 30, 3, 3, tail=0xFD), r"pause frame argument is 3"),
        (_frame(0xFC, 30, 9, 1, tail=0xFD), r"structure mode argument is 1"),
        (_frame(0xFC, 30, 9, 8, tail=0xFD), r"structure mode argument is 8"),
    ],
    ids=["arc-sub-2", "linear-sub-5", "pause-arg-0", "pause-arg-3", "structure-arg-1", "structure-arg-8"],
)
def test_decode_command_rejects_unknown_subcommand_or_argument(frame, message):
    with pytest.raises(FrameError, match=message):
        decode_command(frame)


def _with_slot(frame: bytes, slot: int, raw: bytes) -> bytes:
    start = 3 + 4 * (slot - 1)
    return frame[:start] + raw + frame[start + 4 :]


@pytest.mark.parametrize(
    "frame",
    [
        _frame(0xFC, 30, 2, 16, tail=0xFD),  # program 16
        _frame(0xFC, 30, 5, 4, tail=0xFD),  # pose 4
        _frame(0xFC, 30, 7, 6, 128, tail=0xFD),  # joystick axis 6
        _with_slot(_LINEAR, 7, bytes(4)),  # PWM 0
        _with_slot(_LINEAR, 1, bytes.fromhex("0000c07f")),  # x = NaN
        _with_slot(_LINEAR, 11, bytes.fromhex("0000807f")),  # speed = +inf
        _LINEAR[:1] + b"3" + b"\x07" + _LINEAR[3:],  # joint move, smoothing 7
        _LINEAR[:1] + b"2" + b"\x03" + _LINEAR[3:],  # accelerated move, mode 3
    ],
    ids=["program-16", "pose-4", "joystick-axis-6", "pwm-0", "x-nan", "speed-inf", "smoothing-7", "accel-mode-3"],
)
def test_well_framed_command_with_impossible_field_is_rejected(frame):
    # Out-of-range fields raise FieldError; an unknown sub-command may be either error
    # (protocol.py raises FrameError for linear/arc but FieldError for modes/smoothing).
    with pytest.raises((FrameError, FieldError)):
        decode_command(frame)


@pytest.mark.parametrize(
    "frame",
    [b"", b"\xce\x00\x00\x00\x00\x00\x00\x00", b"\xce" + bytes(7) + b"\x00\xcf", b"\xcf" + bytes(7) + b"\xce",
     b"\x00" + bytes(7) + b"\xcf", b"\xce" + bytes(6) + b"\x06\xcf", b"\xce" + bytes(6) + b"\x65\xcf",
     b"\xce" + bytes(6) + b"\xff\xcf"],
    ids=["empty", "8-bytes", "10-bytes", "swapped", "no-head", "kind-6", "kind-101", "kind-255"],
)
def test_decode_status_rejects_non_frames(frame):
    with pytest.raises(FrameError):
        decode_status(frame)


@pytest.mark.parametrize("raw", ["0000c07f", "0000807f", "000080ff"], ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("kind", [100, 103])
def test_decode_status_rejects_non_finite_float(kind, raw):
    with pytest.raises((FrameError, FieldError)):
        decode_status(b"\xce" + bytes.fromhex(raw) + b"\x00\x00" + bytes([kind]) + b"\xcf")


# --- Hypothesis: round trips ------------------------------------------------------------------

# Any finite float: float32 values, and float64 values that construction rounds to float32.
any_f32 = st.floats(width=32, allow_nan=False, allow_infinity=False) | st.floats(min_value=-F32_MAX, max_value=F32_MAX)
positive_f32 = st.floats(min_value=0, exclude_min=True, allow_infinity=False, width=32)
non_negative_f32 = st.floats(min_value=0, allow_infinity=False, width=32)
pwm = st.floats(min_value=500, max_value=2500)
accel = st.floats(min_value=-3200, max_value=3200)
pose = dict(x_mm=any_f32, y_mm=any_f32, z_mm=any_f32, b0_deg=any_f32, b1_deg=any_f32, w_deg=any_f32)
external = dict(e0_deg=any_f32, e1_deg=any_f32)
joystick_byte = st.integers(0, 255)

COMMANDS = {
    LinearMove: st.builds(
        LinearMove, **pose, **external, pwm_us=pwm, speed_mm_min=positive_f32, pwm_channel=st.integers(1, 4)
    ),
    AccelLinearMove: st.builds(
        AccelLinearMove, **pose, **external, mode=st.sampled_from([0, 1]), accel_mm_s2=accel,
        speed1_mm_min=positive_f32, speed0_mm_min=st.just(0.0),
    ) | st.builds(
        AccelLinearMove, **pose, **external, mode=st.just(2), accel_mm_s2=accel,
        speed1_mm_min=positive_f32, speed0_mm_min=non_negative_f32,
    ),
    JointMove: st.builds(
        JointMove, j1_deg=any_f32, j2_deg=any_f32, j3_deg=any_f32, j4_deg=any_f32, j5_deg=any_f32, j6_deg=any_f32,
        **external, pwm_us=pwm, speed_deg_s=positive_f32, smoothing=st.integers(0, 6),
    ),
    ArcStart: st.builds(ArcStart, **pose, **external, pwm_us=pwm, radius_mm=positive_f32, speed_mm_min=positive_f32),
    ArcEnd: st.builds(ArcEnd, **pose, **external, pwm_us=pwm, speed_mm_min=non_negative_f32),
    Delay: st.builds(Delay, delay_ms=non_negative_f32),
    MCode: st.builds(MCode, number=st.integers(-(2**31), 2**31 - 1)),
    ResetArm: st.builds(ResetArm),
    ResetConnector: st.builds(ResetConnector),
    SetWorktableOrigin: st.builds(SetWorktableOrigin, x_mm=any_f32, y_mm=any_f32, z_mm=any_f32),
    RunProgram: st.builds(RunProgram, program=st.integers(0, 15)),
    PauseToggle: st.builds(PauseToggle),
    GoToPose: st.builds(GoToPose, pose=st.integers(0, 3)),
    Joystick: st.builds(Joystick, axis=st.integers(0, 5), values=st.tuples(joystick_byte))
    | st.builds(Joystick, axis=st.just(100), values=st.tuples(joystick_byte, joystick_byte, joystick_byte)),
    StructureMode: st.builds(StructureMode, mode=st.integers(0, 1)),
}


def _word_values(scale: int):
    """Values a signed 16-bit word at ``scale`` can carry: exact grid points and floats near them."""
    return st.integers(-32768, 32767).map(lambda raw: raw / scale) | st.floats(
        min_value=-32768 / scale, max_value=32767 / scale
    )


STATUSES = {
    PositionStatus: st.builds(PositionStatus, x_mm=_word_values(10), y_mm=_word_values(10), z_mm=_word_values(10)),
    JointsLowStatus: st.builds(JointsLowStatus, j1_deg=_word_values(100), j2_deg=_word_values(100), j3_deg=_word_values(100)),
    JointsHighStatus: st.builds(JointsHighStatus, j4_deg=_word_values(100), j5_deg=_word_values(100), j6_deg=_word_values(100)),
    WorktableStatus: st.builds(WorktableStatus, x_mm=_word_values(10), y_mm=_word_values(10), z_mm=_word_values(10)),
    PauseStatus: st.builds(PauseStatus, pause_state=st.integers(0, 255), pwm_us=st.integers(-32768, 32767)),
    WristStatus: st.builds(WristStatus, w0_deg=_word_values(100), w1_deg=_word_values(100)),
    FileLengthStatus: st.builds(FileLengthStatus, value=any_f32),
    FileStatus: st.builds(FileStatus, raw=st.integers(0, 0xFFFF)),
    RunPositionStatus: st.builds(RunPositionStatus, value=any_f32),
}


def test_strategies_cover_every_class():
    assert set(COMMANDS) == set(MOTION_COMMANDS) | set(CONTROL_COMMANDS)
    assert set(STATUSES) == set(STATUS_KINDS.values())


@pytest.mark.parametrize("cls", list(COMMANDS), ids=lambda c: c.__name__)
@FAST
@given(data=st.data())
def test_command_round_trip(cls, data):
    command = data.draw(COMMANDS[cls])
    frame = command.encode()
    assert len(frame) == 48
    assert (frame[0], frame[47]) in ((0xEE, 0xEF), (0xFC, 0xFD))
    decoded = decode_command(frame)
    assert type(decoded) is cls
    assert decoded == command
    assert decoded.encode() == frame


@pytest.mark.parametrize("cls", list(STATUSES), ids=lambda c: c.__name__)
@FAST
@given(data=st.data())
def test_status_round_trip(cls, data):
    status = data.draw(STATUSES[cls])
    frame = status.encode()
    assert len(frame) == 9 and frame[0] == 0xCE and frame[8] == 0xCF and frame[7] == cls.KIND
    decoded = decode_status(frame)
    assert type(decoded) is cls
    assert decoded == status
    assert decoded.encode() == frame


@FAST
@given(value=st.floats(allow_nan=False, min_value=-F32_MAX, max_value=F32_MAX))
def test_construction_rounds_to_float32_like_struct(value):
    assert SetWorktableOrigin(x_mm=value, y_mm=0, z_mm=0).x_mm == f32(value)


# --- Hypothesis: arbitrary 48-byte frames -------------------------------------------------------


def _slots(*numbers: int) -> set[int]:
    return {3 + 4 * (k - 1) + i for k in numbers for i in range(4)}


_CODE = {0, 1, 2, 47}  # head, a[1], a[2], tail
# The bytes PROTOCOL.md gives a meaning, per command; every other byte is "unused, 0".
MEANINGFUL = {
    LinearMove: _CODE | _slots(1, 2, 3, 4, 5, 6, 7, 8, 9, 11),  # f10 = 0
    AccelLinearMove: _CODE | _slots(*range(1, 12)),
    JointMove: _CODE | _slots(1, 2, 3, 4, 5, 6, 7, 8, 9, 11),  # f10 = 0
    ArcStart: _CODE | _slots(*range(1, 12)),
    ArcEnd: _CODE | _slots(1, 2, 3, 4, 5, 6, 7, 8, 9, 11),  # f10 not used by G301
    Delay: {0, 1, 47} | _slots(1),  # a[2] N/A
    MCode: {0, 1, 47} | _slots(1),  # a[2] N/A
    ResetArm: _CODE,
    ResetConnector: _CODE,
    SetWorktableOrigin: _CODE | _slots(1, 2, 3),
    RunProgram: _CODE | {3},
    PauseToggle: _CODE | {3},
    GoToPose: _CODE | {3},
    StructureMode: _CODE | {3},
}


def meaningful_bytes(command) -> set[int]:
    if isinstance(command, Joystick):
        return _CODE | ({3, 4, 5, 6} if command.axis == 100 else {3, 4})
    return MEANINGFUL[type(command)]


_slot = (
    st.binary(min_size=4, max_size=4)
    | st.just(bytes(4))
    | st.floats(500, 2500, width=32).map(struct.Struct("<f").pack)
    | st.floats(-3200, 3200, width=32).map(struct.Struct("<f").pack)
    | st.sampled_from([0, 1, 2, 3, 4, 5, 9, 15, 16, 100]).flatmap(
        lambda k: st.binary(min_size=3, max_size=3).map(lambda rest: bytes([k]) + rest)
    )
)


# (head, a[1], a[2], tail) of every command, plus sub-commands next to the valid ones
KNOWN_PREFIXES = [(0xEE, ord(code), a2, 0xEF) for code in "1234567" for a2 in range(8)] + [
    (0xFC, a1, a2, 0xFD) for a1, a2 in [(12, 3), (12, 6), (20, 1), (30, 2), (30, 3), (30, 5), (30, 7), (30, 9)]
]


@st.composite
def frame_like(draw) -> bytes:
    """48 bytes shaped like a command often enough to reach every decoder branch."""
    head, a1, a2, tail = draw(
        st.sampled_from(KNOWN_PREFIXES)
        | st.tuples(st.sampled_from([0xEE, 0xFC]), st.integers(0, 255), st.integers(0, 255), st.sampled_from([0xEF, 0xFD]))
        | st.tuples(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255), st.integers(0, 255))
    )
    body = b"".join(draw(st.lists(_slot, min_size=11, max_size=11)))
    if draw(st.booleans()):  # sometimes keep only a few non-zero bytes
        keep = draw(st.sets(st.integers(0, 43), max_size=8))
        body = bytes(b if i in keep else 0 for i, b in enumerate(body))
    return bytes([head, a1, a2]) + body + bytes([tail])


@st.composite
def mutated_command(draw) -> bytes:
    """A valid command frame with a few bytes overwritten anywhere, used or unused."""
    frame = bytearray(draw(st.one_of(*COMMANDS.values())).encode())
    for position in draw(st.lists(st.integers(0, 47), max_size=4)):
        frame[position] = draw(st.integers(0, 255))
    return bytes(frame)


@settings(max_examples=400, deadline=None)
@given(frame=st.one_of(frame_like(), mutated_command(), st.binary(min_size=48, max_size=48)))
@example(frame=_LINEAR[:2] + b"\x00" + _LINEAR[3:])  # a[2]=0: channel 1, re-encoded as 1
@example(frame=_with_slot(_LINEAR, 10, b"\x01\x02\x03\x04"))  # non-zero f10, which a linear move ignores
@example(frame=Delay(delay_ms=5).encode()[:2] + b"\x07" + bytes(44) + b"\xef")  # Delay with a[2]=7 (N/A)
@example(frame=_frame(0xFC, 30, 7, 3, 200, 9, 9, tail=0xFD))  # joint joystick: a[5], a[6] unused
def test_arbitrary_frame_decodes_faithfully_or_raises_frame_or_field_error(frame):
    """Either FrameError/FieldError, or a command that carries the frame's meaningful bytes.

    The weaker property, stated: unused bytes may be non-zero in arbitrary input and the decoder
    ignores them, so we compare encode() with the input only on the bytes PROTOCOL.md gives a
    meaning (plus: the unused ones re-encode as 0).  The one meaningful byte that may change is
    a linear move's a[2]=0, which means channel 1 and is re-encoded as 1.
    """
    try:
        command = decode_command(frame)
    except (FrameError, FieldError):
        return
    reencoded = command.encode()
    meaningful = meaningful_bytes(command)
    expected = bytearray(b if i in meaningful else 0 for i, b in enumerate(frame))
    if isinstance(command, LinearMove) and frame[2] == 0:
        assert reencoded[2] == 1
        expected[2] = 1
    assert reencoded == bytes(expected), hex_diff(reencoded, bytes(expected))
    assert decode_command(reencoded) == command
    # with its unused bytes cleared, the input is exactly what armctl would send
    cleaned = bytes(b if i in meaningful else 0 for i, b in enumerate(frame))
    assert decode_command(cleaned) == command


def test_decode_errors_share_the_armctl_root():
    assert issubclass(FrameError, ArmctlError) and issubclass(FieldError, ArmctlError)
    assert isinstance(decode_status(b"\xce" + bytes(6) + b"\x00\xcf"), StatusFrame)
