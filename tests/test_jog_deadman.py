"""The continuous-jog dead-man switch in virtual time (armctl/jog/deadman.py).

A tiny event-driven driver plays a list of (time, event) against a ``Deadman`` and calls
``poll`` exactly when ``next_deadline()`` asks, as the real loop's ``select`` timeout does; it
records every frame with its time, so each rule of the issue is one assertion on that record.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from armctl.jog.deadman import Deadman, DeadmanTiming, neutral
from armctl.core.protocol import Joystick

TIMING = DeadmanTiming(initial_delay_s=0.5, repeat_gap_s=0.1, line_s=0.05)
J1_PLUS = Joystick(0, (152,))
J1_MINUS = Joystick(0, (104,))
J2_PLUS = Joystick(1, (152,))
X_PLUS = Joystick(100, (188, 128, 128))
REPEAT_S = 0.033  # 30 auto-repeats a second


def play(events, until: float = 5.0, timing: DeadmanTiming = TIMING):
    """events: [(t, "press", command) | (t, "stop")] in time order → [(t, frame)]."""
    deadman = Deadman(timing)
    sent = []
    queue = list(events)
    now = 0.0
    while True:
        deadline = deadman.next_deadline()
        next_event = queue[0][0] if queue else None
        candidates = [t for t in (deadline, next_event) if t is not None]
        if not candidates or min(candidates) > until:
            break
        now = max(now, min(candidates))
        if queue and queue[0][0] <= now:
            event = queue.pop(0)
            frames = deadman.press(event[2], now) if event[1] == "press" else deadman.stop(now)
        else:
            frames = deadman.poll(now)
        sent += [(round(now, 6), frame) for frame in frames]
    return sent, deadman


def held(command, start: float, last: float, delay: float = 0.4):
    """A key held on a keyboard whose auto-repeat starts ``delay`` after the press (shorter
    than the configured 0.5 s) and repeats every 33 ms, until ``last``."""
    events = [(start, "press", command)]
    t = start + delay
    while t <= last + 1e-9:
        events.append((round(t, 6), "press", command))
        t += REPEAT_S
    return events


def test_tap_moves_no_longer_than_the_initial_delay():
    sent, deadman = play([(1.0, "press", J1_PLUS)])
    assert sent[0] == (1.0, J1_PLUS)
    assert len(sent) == 2 and sent[1][1] == neutral(0)
    assert sent[1][0] - sent[0][0] <= TIMING.initial_delay_s
    assert not deadman.moving


def test_held_key_sends_two_frames_and_neutral_within_150ms_of_the_last_repeat():
    events = held(J1_PLUS, 0.0, 2.0)
    last_repeat = events[-1][0]
    sent, _ = play(events)
    assert [frame for _, frame in sent] == [J1_PLUS, neutral(0)]  # no stream of repeats
    assert 0 < sent[1][0] - last_repeat <= 0.150
    assert sent[1][0] - last_repeat <= TIMING.repeat_gap_s


def test_missing_repeats_within_the_gap_keep_moving():
    events = [(0.0, "press", J1_PLUS), (0.4, "press", J1_PLUS), (0.433, "press", J1_PLUS), (0.499, "press", J1_PLUS)]
    sent, _ = play(events)
    assert [t for t, _ in sent] == [0.0, pytest.approx(0.499 + 0.1 - TIMING.wake_margin_s)]


@pytest.mark.parametrize("at", [0.2, 0.9])
def test_stop_sends_neutral_at_once(at):
    sent, _ = play([e for e in held(J1_PLUS, 0.0, 1.5) if e[0] < at] + [(at, "stop")])
    assert sent == [(0.0, J1_PLUS), (at, neutral(0))]


def test_stop_when_still_sends_nothing():
    sent, _ = play([(0.0, "stop")])
    assert sent == []


def test_switching_axis_stops_the_old_one_at_once_and_paces_the_new_one():
    sent, _ = play([(0.0, "press", J1_PLUS), (0.2, "press", J2_PLUS)])
    assert sent[:3] == [(0.0, J1_PLUS), (0.2, neutral(0)), (0.25, J2_PLUS)]
    assert sent[3][1] == neutral(1)


def test_reversing_on_the_same_axis_needs_no_neutral_in_between():
    sent, _ = play([(0.0, "press", J1_PLUS), (0.2, "press", J1_MINUS)])
    assert [f for _, f in sent] == [J1_PLUS, J1_MINUS, neutral(0)]


def test_values_superseded_before_the_line_is_free_are_never_sent():
    fast = Joystick(0, (200,))
    sent, _ = play([(0.0, "press", J1_PLUS), (0.01, "press", J1_MINUS), (0.02, "press", fast)])
    assert sent[:2] == [(0.0, J1_PLUS), (0.05, fast)]


def test_linear_axis_uses_three_values_and_a_three_value_neutral():
    sent, _ = play([(0.0, "press", X_PLUS)])
    assert [f for _, f in sent] == [X_PLUS, Joystick(100, (128, 128, 128))]


def test_first_repeat_after_the_lease_restarts_the_motion():
    # A keyboard whose repeat delay (0.6 s) is longer than the configured one (0.5 s): the tap
    # lease ends, the first repeat starts the axis again as a new press.
    sent, _ = play(held(J1_PLUS, 0.0, 1.2, delay=0.6))
    assert [f for _, f in sent] == [J1_PLUS, neutral(0), J1_PLUS, neutral(0)]
    assert sent[1][0] <= 0.5 and sent[2][0] == pytest.approx(0.6)


def test_refresh_resends_an_unchanged_value_when_asked():
    timing = DeadmanTiming(initial_delay_s=0.5, repeat_gap_s=0.1, line_s=0.05, refresh_s=0.5)
    sent, _ = play(held(J1_PLUS, 0.0, 2.0), timing=timing)
    values = [t for t, f in sent if f == J1_PLUS]
    assert len(values) == 5 and all(b - a == pytest.approx(0.5) for a, b in zip(values, values[1:]))


def test_still_after_is_when_the_last_neutral_has_landed():
    sent, deadman = play([(0.0, "press", J1_PLUS)])
    assert deadman.still_after_s == pytest.approx(sent[-1][0] + TIMING.line_s)


_COMMANDS = [J1_PLUS, J1_MINUS, J2_PLUS, X_PLUS]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 0.7), st.integers(-1, len(_COMMANDS) - 1)), max_size=40))
def test_invariants_for_any_key_sequence(steps):
    events, t = [], 0.0
    for gap, which in steps:
        t = round(t + gap, 6)
        events.append((t, "stop") if which < 0 else (t, "press", _COMMANDS[which]))
    sent, deadman = play(events, until=t + 2.0)
    assert not deadman.moving  # everything stops on its own
    moving: dict[int, Joystick] = {}
    last_event = {}
    for time_s, frame in sent:
        assert frame != moving.get(frame.axis)  # a frame only when the value changes
        if frame.is_still:
            assert frame.axis in moving  # never a neutral for an axis that is still
            moving.pop(frame.axis)
        else:
            moving[frame.axis] = frame
        last_event[frame.axis] = time_s
    # No motion outlives its lease: after the last key, every axis is neutral within the delay.
    last_key = max((e[0] for e in events), default=0.0)
    assert all(time_s <= last_key + TIMING.initial_delay_s + TIMING.line_s for time_s in last_event.values())
