"""A motion frame is decoded in one unpack and built as ``from_fields`` builds it (issue 23: the
simulated arm decodes every frame it is sent): the same command, to the bit, and the same error
for a frame no command holds (NaN, inf, a value out of range, a bad sub-command)."""

from __future__ import annotations

import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core.frame_fields import FLOAT_CODEC, slot_offset
from armctl.core.protocol import AccelLinearMove, ArcEnd, ArcStart, Delay, JointMove, LinearMove
from armctl.core.protocol import decode_command as decode

KINDS = (LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay)


def _reference(kind, frame: bytes):
    """The decoding as it was: one unpack a slot, the command built from keywords."""
    values = {name: FLOAT_CODEC.unpack_from(frame, slot_offset(slot))[0] for name, slot in kind.SLOTS.items()}
    return kind(**values, **kind._ints_from_subcommand(frame[2]))


def _outcome(build):
    try:
        return repr(build())
    except Exception as error:  # noqa: BLE001 - the error itself is compared
        return f"{type(error).__name__}: {error}"


_SLOT = st.one_of(st.floats(width=32, allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1500.0, 60.0]),
                  st.floats(-400, 400, width=32))


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(KINDS), st.lists(_SLOT, min_size=11, max_size=11), st.integers(0, 6))


def test_decode_is_the_keyword_decoding(kind, slots, subcommand):
    frame = bytearray(48)
    frame[0], frame[1], frame[47] = 0xEE, ord(kind.CODE), 0xEF
    frame[2] = (0 if kind is ArcStart else 1) if kind in (ArcStart, ArcEnd) else subcommand
    for slot, value in enumerate(slots, 1):
        FLOAT_CODEC.pack_into(frame, slot_offset(slot), value)
    frame = bytes(frame)
    assert _outcome(lambda: kind._from_frame(frame)) == _outcome(lambda: _reference(kind, frame))
    if kind in (ArcStart, ArcEnd) or subcommand <= 4:
        assert _outcome(lambda: decode(frame)) == _outcome(lambda: _reference(kind, frame))


def test_round_trip_keeps_the_sign_of_zero():
    move = LinearMove(-0.0, 0.0, 150.0, 180.0, -0.0, 0.0, pwm_us=1500.0, speed_mm_min=3000.0, e0_deg=-0.0, pwm_channel=3)
    again = decode(move.encode())
    assert repr(again) == repr(move) and again.encode() == move.encode()
    assert struct.pack("<d", again.x_mm) == struct.pack("<d", -0.0)
