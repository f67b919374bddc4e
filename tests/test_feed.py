"""Feed override (armctl/core/feed.py) against PROTOCOL.md's speed slots and lint's L201.

Strategy: golden bytes written by hand (the speed slot of each scaled frame, as IEEE-754
single little-endian; every other byte identical to the unscaled frame), then Hypothesis:
scaling is monotone in the percentage, 100 % is the identity byte for byte, and every scaled
frame passes lint's own speed rule (L201, called as lint calls it).
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from armctl.core.feed import FeedOverride, clamp_percent, scale_speed
from armctl.lint.rules import speed_above_max
from armctl.host.profile import Speeds
from armctl.core.protocol import AccelLinearMove, ArcEnd, ArcStart, Delay, JointMove, LinearMove, PauseToggle

SPEEDS = Speeds(max_linear_mm_min=6000.0, max_joint_deg_s=120.0, max_accel_mm_s2=3200.0, attitude_deg_s=90.0)
POSE = dict(x_mm=200.0, y_mm=0.0, z_mm=100.0, b0_deg=180.0, b1_deg=0.0, w_deg=0.0)
SPEED_SLOT, SPEED0_SLOT = (43, 47), (27, 31)  # f11 = a[43..46], f7 = a[27..30]

# (command, percent, {slot: the 4 bytes it must carry}, clamped) — floats derived by hand:
# 1500 = 0x44bb8000, 10 = 0x41200000, 1000 = 0x447a0000, 2000 = 0x44fa0000, 300 = 0x43960000,
# 100 = 0x42c80000, 6000 = 0x45bb8000 (3000 = 0x453b8000 with the exponent one up), 120 = 0x42f00000.
GOLDEN = [
    (LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=1000.0), 150, {SPEED_SLOT: "0080bb44"}, False),
    (JointMove(10.0, 20.0, 30.0, 0.0, 0.0, 0.0, pwm_us=1500.0, speed_deg_s=20.0), 50, {SPEED_SLOT: "00002041"}, False),
    (AccelLinearMove(mode=2, **POSE, accel_mm_s2=100.0, speed1_mm_min=1000.0, speed0_mm_min=500.0), 200,
     {SPEED0_SLOT: "00007a44", SPEED_SLOT: "0000fa44"}, False),
    (ArcStart(**POSE, pwm_us=1500.0, radius_mm=50.0, speed_mm_min=1000.0), 30, {SPEED_SLOT: "00009643"}, False),
    (ArcEnd(**POSE, pwm_us=1500.0, speed_mm_min=500.0), 20, {SPEED_SLOT: "0000c842"}, False),
    (LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=5000.0), 200, {SPEED_SLOT: "0080bb45"}, True),
    (JointMove(10.0, 20.0, 30.0, 0.0, 0.0, 0.0, pwm_us=1500.0, speed_deg_s=100.0), 200, {SPEED_SLOT: "0000f042"}, True),
]


@pytest.mark.parametrize("command, percent, slots, clamped", GOLDEN, ids=lambda v: type(v).__name__ if hasattr(v, "encode") else None)
def test_golden_scaled_frames(command, percent, slots, clamped):
    result = scale_speed(command, percent, SPEEDS)
    before, after = command.encode(), result.command.encode()
    expected = bytearray(before)
    for where, hex_bytes in slots.items():
        expected[slice(*where)] = bytes.fromhex(hex_bytes)
    assert after == bytes(expected)
    assert result.clamped is clamped


def test_acceleration_delays_and_control_frames_are_not_scaled():
    accel = AccelLinearMove(mode=1, **POSE, accel_mm_s2=100.0, speed1_mm_min=1000.0)
    assert scale_speed(accel, 50, SPEEDS).command.accel_mm_s2 == 100.0
    for command in (Delay(500.0), PauseToggle()):
        assert scale_speed(command, 50, SPEEDS).command is command


def test_percent_grid_and_steps():
    assert [clamp_percent(p) for p in (0, 10, 14, 15, 100, 200, 250)] == [10, 10, 10, 20, 100, 200, 200]
    feed = FeedOverride(SPEEDS)
    assert [feed.step(+1) for _ in range(12)][-1] == 200
    assert [feed.step(-1) for _ in range(25)][-1] == 10


def test_an_arc_keeps_the_percentage_of_its_first_frame():
    feed = FeedOverride(SPEEDS)
    start = feed.apply(ArcStart(**POSE, pwm_us=1500.0, radius_mm=50.0, speed_mm_min=1000.0))
    feed.set_percent(200)
    end = feed.apply(ArcEnd(**POSE, pwm_us=1500.0, speed_mm_min=1000.0))
    after = feed.apply(LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=1000.0))
    assert (start.speed_mm_min, end.speed_mm_min, after.speed_mm_min) == (1000.0, 1000.0, 2000.0)


def test_clamped_is_shown_until_a_frame_is_not():
    feed = FeedOverride(SPEEDS, percent=200)
    feed.apply(LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=5000.0))
    assert feed.clamped
    feed.apply(Delay(10.0))  # no speed: says nothing either way
    assert feed.clamped
    feed.apply(LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=100.0))
    assert not feed.clamped


# --- properties ------------------------------------------------------------------------------

percents = st.integers(1, 20).map(lambda k: 10 * k)
linear_speeds = st.floats(0.001, SPEEDS.max_linear_mm_min)
joint_speeds = st.floats(0.001, SPEEDS.max_joint_deg_s)


@st.composite
def speed_commands(draw):
    kind = draw(st.sampled_from(["G1", "G6", "G230", "G222", "G300", "G301"]))
    if kind == "G1":
        return LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=draw(linear_speeds))
    if kind == "G6":
        return JointMove(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, pwm_us=1500.0, speed_deg_s=draw(joint_speeds))
    if kind == "G230":
        return AccelLinearMove(mode=2, **POSE, accel_mm_s2=100.0, speed1_mm_min=draw(linear_speeds),
                               speed0_mm_min=draw(st.floats(0.0, SPEEDS.max_linear_mm_min)))
    if kind == "G222":
        return AccelLinearMove(mode=1, **POSE, accel_mm_s2=100.0, speed1_mm_min=draw(linear_speeds))
    if kind == "G300":
        return ArcStart(**POSE, pwm_us=1500.0, radius_mm=50.0, speed_mm_min=draw(linear_speeds))
    return ArcEnd(**POSE, pwm_us=1500.0, speed_mm_min=draw(st.floats(0.0, SPEEDS.max_linear_mm_min)))


def _speeds(command) -> tuple:
    return tuple(getattr(command, name) for name in ("speed_mm_min", "speed_deg_s", "speed0_mm_min", "speed1_mm_min")
                 if hasattr(command, name))


def _l201_findings(command) -> list:
    """L201 as lint runs it, on a statement whose words are what the frame carries."""
    words = {"F": _speeds(command)[-1]}
    if isinstance(command, AccelLinearMove) and command.mode == 2:
        words["Q"] = command.speed0_mm_min
    statement = SimpleNamespace(command=command, words=words)
    return list(speed_above_max(statement, SimpleNamespace(profile=SimpleNamespace(speed=SPEEDS))))


@given(speed_commands())
def test_100_percent_is_the_identity_byte_for_byte(command):
    assert scale_speed(command, 100, SPEEDS).command.encode() == command.encode()


@given(speed_commands(), percents, percents)
def test_scaling_is_monotone(command, low, high):
    low, high = sorted((low, high))
    slow, fast = _speeds(scale_speed(command, low, SPEEDS).command), _speeds(scale_speed(command, high, SPEEDS).command)
    assert all(a <= b for a, b in zip(slow, fast))


@given(speed_commands(), percents)
def test_every_scaled_frame_passes_the_lint_speed_rule(command, percent):
    assert _l201_findings(command) == []  # the precondition: a job that passed lint
    scaled = scale_speed(command, percent, SPEEDS).command
    assert _l201_findings(scaled) == []
    scaled.encode()  # and it is a frame (a positive speed stays positive)


def test_the_lint_speed_rule_in_the_property_can_fail():
    too_fast = LinearMove(**POSE, pwm_us=1500.0, speed_mm_min=6000.5)
    assert _l201_findings(too_fast)
