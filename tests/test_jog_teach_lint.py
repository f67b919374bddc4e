"""A taught file always lints clean (issue 10): whatever the arm reports, the line jog writes
for it has no lint error — values outside the language's ranges are clamped and the line's
comment says so.  Linted against the built-in profile (findings on its illustrative numbers are
warnings); against a user's profile a taught pose outside that profile's limits is a true finding.
"""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.jog.moves import Reported
from armctl.jog.teach import FILE_HEADER, taught_line
from armctl.lint import lint_lines
from armctl.host.profile import default_profile

WHEN = datetime(2024, 5, 1, 14, 30, 5, tzinfo=timezone(timedelta(hours=2)))


def _status(scale: int) -> st.SearchStrategy[float]:
    """A value as a status word carries it: a signed 16-bit integer over ``scale``."""
    return st.integers(-32768, 32767).map(lambda word: word / scale)


def _reported(joints, xyz, pwm, origin) -> Reported:
    attitude = tuple(default_profile().kinematics.forward(joints)[3:6])  # as moves.reported_pose does
    return Reported(xyz, attitude, joints, float(pwm), origin)


# X/Y/Z and the worktable origin within ±270 mm each, so the robot-frame target stays within twice
# the built-in profile's reach (940 mm): a report beyond that is no desktop arm's (a corrupted
# word), and lint's L103 refuses such a target as an error (issue 26) — a true finding, not the
# teacher's fault.
PLAUSIBLE_MM = st.integers(-2700, 2700).map(lambda word: word / 10)
REPORTED = st.builds(
    _reported,
    st.tuples(*[_status(100)] * 6),  # joints, 0.01 deg
    st.tuples(*[PLAUSIBLE_MM] * 3),  # X/Y/Z, 0.1 mm
    st.integers(-32768, 32767),  # PWM, µs
    st.tuples(*[PLAUSIBLE_MM] * 3),
)
SPEED = st.floats(min_value=1e-3, max_value=1e5, allow_nan=False)  # jog's levels: positive numbers


def lint_errors(text: str) -> list[str]:
    """Every error but E012: a job longer than a day (lint's motion-time bound) is a true finding
    about the speed level taught with (jog's slowest, 0.01 deg/s or 0.1 mm/min, over a long way),
    not about the line the teacher wrote."""
    report = lint_lines(text.splitlines(), "taught.txt", default_profile())
    return [str(d) for d in report.diagnostics if d.is_error and d.code != "E012"]


@settings(max_examples=150, deadline=None)
@given(st.sampled_from(["joint", "linear"]), REPORTED, SPEED)
def test_any_reported_state_teaches_a_line_that_lints_with_no_error(mode, reported, speed):
    line = taught_line(mode, reported, speed, WHEN)
    assert lint_errors(FILE_HEADER + line) == [], line


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["joint", "linear"]), REPORTED, SPEED), min_size=1, max_size=5))
def test_a_taught_file_lints_with_no_error(taught):
    text = FILE_HEADER + "".join(taught_line(mode, reported, speed, WHEN) for mode, reported, speed in taught)
    assert lint_errors(text) == [], text


def test_a_pwm_of_0_is_clamped_and_the_comment_says_why():
    reported = _reported((0.0, 0.0, 0.0, 0.0, 90.0, 0.0), (250.0, 0.0, 150.0), 0, (0.0, 0.0, 0.0))
    line = taught_line("joint", reported, 30.0, WHEN)
    assert " S500 F30 ; taught " in line
    assert "the arm reported PWM 0 us, outside the language's 500-2500 us: written as S500" in line
    high = taught_line("linear", _reported((0.0,) * 6, (250.0, 0.0, 150.0), 3000, (0.0,) * 3), 1500.0, WHEN)
    assert " S2500 F1500 ; " in high and "reported PWM 3000 us" in high


def test_a_pwm_inside_the_range_has_no_note():
    reported = _reported((0.0, 0.0, 0.0, 0.0, 90.0, 0.0), (250.0, 0.0, 150.0), 1000, (0.0, 0.0, 0.0))
    assert taught_line("joint", reported, 30.0, WHEN).endswith("S1000 F30 ; taught 2024-05-01T14:30:05+02:00\n")
