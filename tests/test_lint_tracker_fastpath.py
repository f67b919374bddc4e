"""``ArmTracker.apply``'s LinearMove shortcut leaves the tracker as ``apply_any`` (the general
path) leaves it, on compiled scripts of every kind of statement (issue 13)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.lint.tracker import ArmTracker
from armctl.host.profile import default_profile
from armctl.script import compile_lines

PROFILE = default_profile()
_LINES = st.sampled_from([
    "G1 X250 Y0 Z150 A180 B0 C0 F3000 S1000", "G1 X240 Y10", "G1 Z120 S1500", "G1 T2 S1800", "G1 T3", "G1 X230 T1 S900",
    "G1 A170 B5 C-10", "G1 U5 V-3", "G6 J1=0 J2=10 J3=20 J4=0 J5=30 J6=0 F30 S1200", "POSE 1", "G54 X10 Y-5 Z0",
    "G300 X260 Y20 Z150 R20", "G301 X270 Y0 Z150", "PAUSE", "G4 P100", "RESET", "G220 X250 Y5 Z150 K100 F3000",
])


def _state(tracker):
    return {name: value for name, value in vars(tracker).items() if not name.startswith("_")}


@settings(max_examples=200, deadline=None)
@given(st.lists(_LINES, min_size=1, max_size=30))
def test_apply_is_apply_any(lines):
    fast, slow = ArmTracker(PROFILE), ArmTracker(PROFILE)
    for statement in compile_lines(lines):
        fast.apply(statement)
        slow.apply_any(statement)
        assert _state(fast) == _state(slow)


def test_the_shortcut_is_taken_and_tracks_pwm():
    fast = ArmTracker(PROFILE)
    statements = list(compile_lines(["G1 X250 Y0 Z150 A180 B0 C0 F3000 S1000", "G1 T2 S1800"]))
    for statement in statements:
        fast.apply(statement)
    assert fast.pose == (250.0, 0.0, 150.0, 180.0, 0.0, 0.0)
    assert fast.pwm_us == {1: 1000.0, 2: 1800.0} and fast.pwm_statement[2] is statements[1]
