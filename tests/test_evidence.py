"""armctl/core/evidence.py: the rules of arm evidence, once — and the places that used to restate them
give the answers they gave (the old code kept here as the reference)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core.evidence import (
    AGREEING_REPORTS, REST_CHECK_S, agreed, agreeing_runs, beyond_reach, known_still_s, reach, still_long_enough,
)
from armctl.core.job_control import agreed_pause
from armctl.probe.plan import Seen
from armctl.core.protocol import PauseStatus


def _old_agreed_pause(reports):  # job_control.agreed_pause before issue 23
    reports = tuple(reports)[-2:]
    if len(reports) == 2 and reports[0] == reports[1]:
        return reports[0]
    return None


def _old_seen_agreed(entries, until_s):  # probe/plan.py Seen.agreed before issue 23
    run, value, start_s, best = 0, None, None, None
    for t, current in entries:
        if t > until_s:
            break
        if run and current == value:
            run += 1
        else:
            run, value, start_s = 1, current, t
        if run >= 2:
            best = (start_s, value)
    return best


def _old_paused_since(entries):  # probe/steps.py _paused_since before issue 23
    run_start_s, count = None, 0
    for t, paused in entries:
        if paused:
            run_start_s, count = (t, 1) if count == 0 else (run_start_s, count + 1)
            if count >= 2:
                return run_start_s, t
        else:
            count = 0
    return None


@pytest.mark.parametrize("reports, expected", [
    ((), None), ((True,), None), ((True, False), None), ((False, True, True), True), ((True, False, False), False),
    ((None, None), None),
])
def test_two_agreeing_reports(reports, expected):
    assert AGREEING_REPORTS == 2
    assert agreed(reports) is expected
    assert agreed_pause(reports) is expected


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from([True, False, None]), max_size=6))
def test_the_pause_rule_answers_as_before(reports):
    assert agreed_pause(reports) is _old_agreed_pause(reports)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.integers(0, 2), max_size=12), st.integers(-1, 12))
def test_the_probes_agreed_readings_are_as_before(states, until):
    seen = Seen(transit_s=0.0)
    for k, state in enumerate(states):
        seen.feed(PauseStatus(state, 1500), k * 0.03)
    entries = [(t, frame.pause_state) for t, frame in seen.since(PauseStatus.KIND, float("-inf"))]
    until_s = until * 0.03
    assert seen.agreed(PauseStatus.KIND, key=lambda f: f.pause_state, until_s=until_s) == _old_seen_agreed(entries, until_s)
    paused = [(t, state != 0) for t, state in entries]
    first = next(((start, confirmed) for start, confirmed, value in agreeing_runs(paused) if value), None)
    assert first == _old_paused_since(paused)


def test_agreeing_runs_say_when_each_run_began_and_was_confirmed():
    readings = [(0.0, 1), (1.0, 2), (2.0, 2), (3.0, 2), (4.0, 1), (5.0, 1)]
    assert agreeing_runs(readings) == [(1.0, 2.0, 2), (4.0, 5.0, 1)]


def test_a_jump_is_beyond_reach_and_a_nan_never_is():
    limit = reach(100.0, 0.03, 2.0)
    assert limit == pytest.approx(5.0)
    assert reach(100.0, -1.0, 2.0) == 2.0  # a negative time moves nothing
    assert beyond_reach((0.0, 0.0, 0.0), (0.0, 5.5, 0.0), limit)
    assert not beyond_reach((0.0, 0.0, 0.0), (4.9, -4.9, 0.0), limit)
    assert not beyond_reach((0.0, 0.0, 0.0), (math.nan, 0.0, 0.0), limit)


def test_rest_is_known_only_up_to_the_oldest_kinds_last_report():
    # changed at 1.0; position and joints read at 2.0, the joints 4-6 last at 1.5 (reports lost since)
    assert known_still_s(1.0, [2.0, 2.0, 1.5]) == 0.5
    assert not still_long_enough(1.0, [2.0, 2.0, 1.5])
    assert still_long_enough(1.0, [2.0, 2.0, 1.0 + REST_CHECK_S])
