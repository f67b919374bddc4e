"""``motion.arc_length_bound_mm``: the longest arc through a G300's point to its end from a start
known only within a ball (a joint move's end on an arm whose kinematics are unverified).  The
streamer's time bound rests on it (a bound too short confirmed an arc the arm was still running:
tests/test_streamer_found_overstatement.py), so it is held against the arcs themselves."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.motion import arc_length_bound_mm, arc_through

coordinate = st.floats(-300, 300, allow_nan=False)
point = st.tuples(coordinate, coordinate, coordinate)
unit = st.floats(-1, 1, allow_nan=False)


@settings(max_examples=400, deadline=None)
@given(start=point, via=point, end=point, error_mm=st.floats(0.1, 60), offset=st.tuples(unit, unit, unit),
       scale=st.floats(0, 1))
def test_no_arc_from_a_start_within_the_ball_is_longer_than_the_bound(start, via, end, error_mm, offset, scale):
    bound = arc_length_bound_mm(start, via, end, error_mm)
    norm = math.sqrt(sum(c * c for c in offset))
    if norm == 0:
        return
    true_start = tuple(s + c / norm * error_mm * scale for s, c in zip(start, offset))
    arc = arc_through(true_start, via, end)
    chord = math.dist(true_start, end)
    length = chord if arc is None else arc.length_mm  # in line: the arm's straight line
    assert length <= bound * (1 + 1e-9) + 1e-9


def test_a_start_in_the_ball_around_the_via_or_in_line_beyond_it_has_no_bound():
    assert arc_length_bound_mm((0.0, 0.0, 0.0), (5.0, 0.0, 0.0), (100.0, 0.0, 0.0), 10.0) == math.inf
    # start, end, via in that order on a line: the arc through them goes round a huge circle
    assert arc_length_bound_mm((0.0, 0.0, 0.0), (200.0, 0.0, 0.0), (100.0, 0.0, 0.0), 1.0) == math.inf


def test_a_half_circle_far_from_the_ball_is_bounded_near_its_length():
    start, via, end = (-100.0, 0.0, 0.0), (0.0, 100.0, 0.0), (100.0, 0.0, 0.0)
    bound = arc_length_bound_mm(start, via, end, 1.0)
    assert math.pi * 100 <= bound < math.pi * 100 * 1.05
