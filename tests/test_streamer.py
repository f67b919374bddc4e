"""The streamer's soundness and pacing rules, with status frames made by hand, in virtual time.

Soundness: the lower bound of frames consumed moves only on evidence — two agreeing
observations, or the time bound that counts only time the arm was seen running — so a
corrupted frame, a pause or silence can never make it claim a frame the arm has not finished.
"""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core.motion import MotionModel, distance_to_path
from armctl.host.profile import load_profile, parse_profile
from armctl.core.protocol import (
    ArcEnd, ArcStart, Delay, JointMove, JointsLowStatus, LinearMove, MCode, PauseStatus,
    PositionStatus,
)
from armctl.core.streamer import (
    ARRIVAL_SLACK_S, CAPACITY_MARGIN_FRAMES, FEED_AHEAD_S, FRAME_SLACK_S, SCAN_WINDOW_FRAMES, SLOWEST_ARM_FACTOR,
    Streamer,
)

MODEL = MotionModel(load_profile())
START = MODEL.initial_pose()  # home: X210 Y0 Z300, tool down
DOWN = (180.0, 0.0, 0.0)
FRAME_S = 0.05


def line(x, y, z, speed=6000.0, pwm=1500.0, w=0.0):
    return LinearMove(x, y, z, 180.0, 0.0, w, pwm, speed)


def streamer(**kw) -> Streamer:
    return Streamer(MODEL, START, **kw)


def write_all(s: Streamer, commands, now: float = 0.0) -> float:
    """Write ``commands`` back to back at the line rate; the time the last one left the host."""
    for command in commands:
        now = max(now, s.wire_free_s)
        s.wrote(command, now)
    return s.wire_free_s


def at(x, y, z) -> PositionStatus:
    return PositionStatus(x, y, z)


def running(pwm=1500):
    return PauseStatus(0, pwm)


def paused(pwm=1500):
    return PauseStatus(1, pwm)


def point_on(s: Streamer, index: int, fraction: float) -> PositionStatus:
    """The status frame an arm ``fraction`` along frame ``index``'s path would send."""
    segment = s.pending[index - s.pending[0].index].segment
    x, y, z = segment.sample(segment.time_at_fraction(fraction)).xyz
    return at(round(x, 1), round(y, 1), round(z, 1))


# --- evidence from positions ------------------------------------------------------------------

A, B, C = (250.0, 0.0, 300.0), (250.0, 100.0, 300.0), (200.0, 100.0, 250.0)


def three_lines() -> Streamer:
    s = streamer()
    write_all(s, [line(*A), line(*B), line(*C)])
    return s


def test_two_agreeing_positions_move_the_bound_to_the_segment_seen():
    s = three_lines()
    s.receive_status(point_on(s, 1, 0.5), 1.0)
    assert s.consumed_lower_bound == 0  # one observation alone proves nothing
    s.receive_status(point_on(s, 1, 0.6), 1.27)
    assert s.consumed_lower_bound == 1  # frame 0 has left the FIFO; frame 1 is running


def test_a_single_corrupted_position_does_not_move_the_bound():
    s = three_lines()
    s.receive_status(point_on(s, 0, 0.3), 0.5)  # genuine: on the first segment
    s.receive_status(point_on(s, 2, 0.5), 0.77)  # corrupted: claims the third
    assert s.consumed_lower_bound == 0
    s.receive_status(point_on(s, 0, 0.9), 1.04)  # genuine again
    assert s.consumed_lower_bound == 0


def test_a_corrupted_frame_first_and_a_genuine_one_after_move_it_only_to_the_genuine_one():
    s = three_lines()
    s.receive_status(point_on(s, 2, 0.5), 0.5)  # corrupted
    s.receive_status(point_on(s, 1, 0.2), 0.77)  # genuine
    assert s.consumed_lower_bound == 1


def test_a_position_off_every_path_is_no_evidence():
    s = three_lines()
    for k in range(5):
        s.receive_status(at(0.0, -300.0, 50.0), 0.3 + 0.27 * k)
    assert s.consumed_lower_bound == 0


def test_repeated_targets_take_the_earliest_candidate():
    s = streamer()
    write_all(s, [line(*A), line(*B), line(*C), line(*B), line(*C)])
    # The arm at B: end of frame 1, start of frame 2, end of frame 3, start of frame 4.
    s.receive_status(at(*B), 2.0)
    s.receive_status(at(*B), 2.27)
    assert s.consumed_lower_bound == 1  # only frame 0 is proven done
    # Half-way from B to C: frame 2 or frame 4 — the earliest, frame 2.
    s.receive_status(point_on(s, 2, 0.5), 2.54)
    s.receive_status(point_on(s, 2, 0.7), 2.81)
    assert s.consumed_lower_bound == 2


def test_an_arc_start_finishes_only_with_its_arc():
    """The arm holds a G300 at the head and runs it with its G301: seeing the arm on the arc
    proves the frames before the G300 done, not the G300 itself."""
    s = streamer()
    write_all(s, [line(*A), ArcStart(230.0, 60.0, 300.0, *DOWN, 1500.0, 60.0, 3000.0),
                  ArcEnd(*B, *DOWN, 1500.0, 3000.0), line(*C)])
    s.receive_status(point_on(s, 2, 0.4), 2.0)
    s.receive_status(point_on(s, 2, 0.5), 2.27)
    assert s.consumed_lower_bound == 1  # frame 0 only; the G300 (frame 1) is still running
    s.receive_status(point_on(s, 3, 0.5), 5.0)
    s.receive_status(point_on(s, 3, 0.6), 5.27)
    assert s.consumed_lower_bound == 3


def test_an_arc_start_is_never_confirmed_by_time_before_its_arc_end_is_written():
    s = streamer()
    write_all(s, [ArcStart(230.0, 60.0, 300.0, *DOWN, 1500.0, 60.0, 3000.0)])
    for k in range(1, 40):
        s.receive_status(running(), 0.27 * k)
    assert s.consumed_lower_bound == 0


def test_an_arc_start_left_alone_is_confirmed_by_time_once_the_next_frame_is_written():
    s = streamer()
    write_all(s, [ArcStart(230.0, 60.0, 300.0, *DOWN, 1500.0, 60.0, 3000.0), MCode(1)])
    s.receive_status(running(), 1.0)
    assert s.all_consumed


# --- joints -----------------------------------------------------------------------------------


def test_joint_halves_confirm_joint_moves():
    s = streamer()
    q1 = (30.0, 10.0, 10.0, 0.0, 70.0, 0.0)
    q2 = (-30.0, 20.0, 0.0, 0.0, 70.0, 0.0)
    write_all(s, [JointMove(*q1, 1500.0, 60.0), JointMove(*q2, 1500.0, 60.0)])
    s.receive_status(JointsLowStatus(0.0, 15.0, 5.0), 2.0)  # halfway along the second move
    s.receive_status(JointsLowStatus(-6.0, 16.0, 4.0), 2.27)
    assert s.consumed_lower_bound == 1


def test_joint_halves_prove_nothing_while_a_cartesian_segment_is_pending_before_them():
    s = streamer()
    write_all(s, [line(*A), JointMove(30.0, 10.0, 10.0, 0.0, 70.0, 0.0, 1500.0, 60.0)])
    s.receive_status(JointsLowStatus(15.0, 5.0, 5.0), 2.0)
    s.receive_status(JointsLowStatus(16.0, 5.3, 5.3), 2.27)
    assert s.consumed_lower_bound == 0


@pytest.mark.parametrize("target", [(160.0, 40.0, -30.0, 0.0, 60.0, 0.0), (-150.0, 30.0, 20.0, 40.0, 80.0, 90.0)])
def test_a_wide_joint_move_matches_its_own_true_trace(target):
    """With verified kinematics, positions are matched against 16 chords of a joint move's trace;
    the tolerance must cover how far the true trace bows away from them, or a later segment could win."""
    verified = MotionModel(parse_profile({"connector": {"kinematics_verified": True}}))
    s = Streamer(verified, verified.initial_pose())
    write_all(s, [JointMove(*target, 1500.0, 90.0)])
    sent = s.pending[0]
    worst = max(distance_to_path(sent.segment, sent.segment.sample(sent.segment.duration_s * k / 400).xyz)[0]
                for k in range(401))
    assert worst > 0.5  # wide enough that the plain position tolerance would miss
    assert worst + 0.1 <= sent.xyz_tolerance_mm


# --- the time bound ---------------------------------------------------------------------------


def test_the_time_bound_confirms_a_delay_once_even_a_slow_arm_is_done():
    s = streamer()
    write_all(s, [Delay(1000.0)])
    certain = FRAME_S + ARRIVAL_SLACK_S + 1.0 * SLOWEST_ARM_FACTOR + FRAME_SLACK_S
    s.receive_status(running(), certain - 0.01)
    assert s.consumed_lower_bound == 0
    s.receive_status(running(), certain + 0.01)
    assert s.consumed_lower_bound == 1
    assert s.all_consumed


def test_no_time_credit_without_news_of_a_running_arm():
    """Positions alone say nothing about a delay; silence about the pause state stops the clock."""
    s = streamer()
    write_all(s, [Delay(1000.0)])
    for k in range(40):
        s.receive_status(at(210.0, 0.0, 300.0), 0.27 * k)
    assert s.consumed_lower_bound == 0


def test_no_time_credit_while_paused():
    s = streamer()
    write_all(s, [Delay(1000.0)])
    s.receive_status(running(), 0.1)
    s.receive_status(paused(), 0.37)  # the pause may have begun right after 0.1
    s.receive_status(paused(), 5.0)
    assert s.consumed_lower_bound == 0
    s.receive_status(running(), 5.27)  # resumed: everything pending waited 5.17 s more
    assert s.consumed_lower_bound == 0
    certain = FRAME_S + ARRIVAL_SLACK_S + 1.0 * SLOWEST_ARM_FACTOR + FRAME_SLACK_S + (5.27 - 0.1)
    s.receive_status(running(), certain - 0.01)
    assert s.consumed_lower_bound == 0
    s.receive_status(running(), certain + 0.01)
    assert s.consumed_lower_bound == 1


def test_one_corrupted_running_state_during_a_pause_gives_no_credit():
    s = streamer()
    write_all(s, [Delay(1000.0)])
    s.receive_status(running(), 0.1)
    s.receive_status(paused(), 0.37)
    s.receive_status(running(), 3.0)  # corrupted: the arm is still paused
    s.receive_status(paused(), 3.27)
    s.receive_status(paused(), 10.0)
    assert s.consumed_lower_bound == 0
    s.receive_status(running(), 10.27)  # the real resume
    s.receive_status(running(), 10.27 + 1.0)
    assert s.consumed_lower_bound == 0  # it needs 2 s of running time after the resume


def test_the_time_bound_restarts_from_evidence_after_a_long_busy_stretch():
    """Chained from the job's start, the bound drifts ahead by the slowest-arm factor for as
    long as the arm is kept busy; agreeing evidence restarts it where the arm was seen."""
    s = streamer()
    points = [(200.0 + 3.0 * k, 100.0 if k % 2 else -100.0, 250.0) for k in range(30)]  # ~2 s each
    write_all(s, [line(*p) for p in points] + [Delay(100.0), MCode(3), Delay(100.0)])
    motion = sum(f.segment.duration_s for f in s.pending)
    assert s.pending[-1].certain_end_s > 1.9 * motion
    seen = motion + 2.0  # the arm has done every move and stands at the last target
    s.receive_status(running(), seen - 0.1)
    s.receive_status(at(*points[-1]), seen)
    s.receive_status(at(*points[-1]), seen + 0.27)
    assert s.consumed_lower_bound == 29  # the last move is the earliest frame at that point
    last_move = s.pending[0].segment.duration_s
    s.receive_status(running(), seen + 0.3)
    assert not s.all_consumed
    done_by = seen + 0.27 + SLOWEST_ARM_FACTOR * (last_move + 0.2) + 4 * FRAME_SLACK_S
    s.receive_status(running(), done_by + 0.01)
    assert s.all_consumed
    assert done_by < 1.2 * motion


# --- pacing -----------------------------------------------------------------------------------


def test_writes_are_paced_to_the_line():
    s = streamer()
    s.wrote(MCode(1), 0.0)
    assert s.next_write_time(0.0) == pytest.approx(FRAME_S)
    assert not s.may_write(0.01)


def test_next_write_time_is_none_at_capacity_minus_margin():
    s = streamer()
    limit = 200 - CAPACITY_MARGIN_FRAMES
    now = write_all(s, [MCode(k) for k in range(limit - 1)])
    assert s.next_write_time(now, MCode(0)) is not None
    now = write_all(s, [MCode(0)], now)
    assert s.frames_in_flight_bound == limit
    assert s.next_write_time(now) is None
    assert s.next_write_time(now + 100.0, MCode(0)) is None  # only evidence can allow it
    assert not s.may_write(now + 100.0)
    s.receive_status(running(), now + 1.0)  # the time bound: M codes take no time
    assert s.next_write_time(now + 1.0) is not None


def test_a_smaller_fifo_and_margin_are_honoured():
    s = streamer(capacity=20, margin=2)
    now = write_all(s, [MCode(k) for k in range(18)])
    assert s.next_write_time(now) is None


def test_the_lead_bounds_the_motion_waiting_behind_the_move_in_progress():
    s = streamer(lead_s=2.0)
    first = line(250.0, 0.0, 150.0)  # 155 mm from home: 1.55 s
    s.wrote(first, 0.0)
    second = line(250.0, 120.0, 150.0)  # 1.2 s
    assert s.next_write_time(FRAME_S, second) == pytest.approx(FRAME_S)  # 1.2 s waits: ≤ 2 s
    s.wrote(second, FRAME_S)
    third = line(250.0, 0.0, 150.0)  # 1.2 s more would make 2.4 s waiting
    when = s.next_write_time(2 * FRAME_S, third)
    assert when == pytest.approx(s.pending[0].est_end_s)  # once the second move has begun
    assert s.waiting_seconds(when + 1e-6) + 1.2 <= 2.0 + 1e-6
    # Without the command the lead is checked before the write.
    assert s.next_write_time(2 * FRAME_S) == pytest.approx(2 * FRAME_S)


def test_a_move_longer_than_the_lead_goes_when_little_is_left():
    s = streamer(lead_s=1.0)
    s.wrote(line(250.0, 0.0, 150.0), 0.0)  # 1.55 s
    long_move = line(250.0, 200.0, 150.0)  # 2 s: longer than the lead by itself
    when = s.next_write_time(FRAME_S, long_move)
    assert when == pytest.approx(s.pending[-1].est_end_s - min(1.0, FEED_AHEAD_S))


def test_writing_does_not_wait_for_zero_length_frames_queued():
    s = streamer(lead_s=0.5)
    now = write_all(s, [MCode(k) for k in range(30)])
    assert s.next_write_time(now, MCode(0)) == pytest.approx(now)


def test_lead_must_be_positive():
    with pytest.raises(ValueError):
        streamer(lead_s=0.0)


# --- the estimate -------------------------------------------------------------------------------


def test_a_paused_arm_holds_the_estimate_back():
    s = streamer()
    write_all(s, [line(*A), line(*B)])
    finish = s.estimated_finish_s()
    for k in range(20):  # the arm stands mid-way along frame 1 for 5 s
        s.receive_status(point_on(s, 1, 0.5), 2.0 + 0.27 * k)
    assert s.estimated_finish_s() > finish + 4.0
    assert s.queued_seconds(2.0 + 0.27 * 19) == pytest.approx(0.5, abs=0.05)


def test_a_still_frame_seen_where_the_estimate_expects_it_does_not_move_the_estimate():
    s = streamer()
    write_all(s, [line(*A), line(*A, pwm=2000.0), Delay(500.0)])
    ends = [f.est_end_s for f in s.pending]
    during_pwm = ends[0] + 0.1
    s.receive_status(at(*A), during_pwm)
    assert [f.est_end_s for f in s.pending] == pytest.approx(ends)


def test_an_arm_seen_at_the_end_before_the_estimate_pulls_it_earlier():
    s = streamer()
    write_all(s, [line(*A), line(*B)])
    end0 = s.pending[0].est_end_s
    s.receive_status(point_on(s, 1, 0.0), end0 - 0.3)  # a faster arm: already at B's start
    assert s.pending[0].est_end_s == pytest.approx(end0 - 0.3, abs=0.02)


# --- the windowed search: flat cost, never a stronger claim than a full search --------------------


def _full_scan_earliest(s: Streamer, xyz):
    """The earliest pending frame whose path passes within its tolerance of ``xyz`` (all searched)."""
    for sent in s.pending:
        if distance_to_path(sent.segment, xyz)[0] <= sent.xyz_tolerance_mm:
            return sent.index
    return None


@settings(max_examples=60, deadline=None)
@given(
    points=st.lists(st.sampled_from([A, B, C, (220.0, -50.0, 280.0), (260.0, 40.0, 260.0)]), min_size=2, max_size=70),
    seen=st.tuples(st.integers(0, 69), st.floats(0.0, 1.0)),
    now=st.floats(0.0, 80.0),
)
def test_the_windowed_search_never_claims_more_than_a_full_search(points, seen, now):
    s = streamer(capacity=1000)
    write_all(s, [line(*p) for p in points])
    index, fraction = seen[0] % len(points), seen[1]
    segment = s.pending[index].segment
    xyz = segment.sample(segment.time_at_fraction(fraction)).xyz
    earliest, candidates = s._scan(lambda sent: (0.0, 1.0) if distance_to_path(sent.segment, xyz)[0]
                                   <= sent.xyz_tolerance_mm else None, len(s.pending), now)
    truth = _full_scan_earliest(s, xyz)
    assert truth is not None and earliest is not None
    assert earliest <= truth  # never further than the arm can be proven to be
    if truth < SCAN_WINDOW_FRAMES:
        assert earliest == truth  # where the evidence usually is, exactly as strong
    assert [c[0] for c in candidates] == sorted(c[0] for c in candidates)


def test_a_match_only_beyond_the_oldest_frames_proves_only_the_first_frame_not_searched():
    s = streamer(capacity=1000)
    far = (200.0, -100.0, 200.0)
    write_all(s, [line(250.0, 0.0, 300.0 - k % 2) for k in range(40)] + [line(*far)])
    tail = s.pending[-1]
    end = tail.segment.end.xyz
    earliest, candidates = s._scan(
        lambda sent: (0.9, 1.0) if distance_to_path(sent.segment, end)[0] <= 0.5 else None, len(s.pending),
        tail.est_end_s)
    assert candidates and candidates[-1][0] == tail.index
    assert earliest == SCAN_WINDOW_FRAMES  # not the far frame: the frames between were not searched


def test_status_with_nothing_pending_is_harmless():
    s = streamer()
    s.wrote(line(*A), 0.0)
    s.confirm_all_done()
    for frame in (at(*A), JointsLowStatus(0.0, 0.0, 0.0), running()):
        s.receive_status(frame, 5.0)
    assert s.all_consumed and s.consumed_lower_bound == 1


# --- the lead holds behind a long move ------------------------------------------------------------


def _zigzag(n, step_mm=4.0):
    """4 mm moves at 6000 mm/min: 40 ms each, shorter than a frame on the wire (50 ms)."""
    return [line(250.0, step_mm * ((k % 2) + 1), 150.0) for k in range(n)]


def test_line_bound_frames_behind_a_long_move_wait_for_the_lead():
    """The stop bound is not traded for the line's pace: behind a long move, short line-bound
    moves go only while the motion waiting behind the move in progress stays within the lead,
    so the line idles during most of the long move (bench: the longfirst row)."""
    s = streamer(lead_s=1.0)
    s.wrote(line(250.0, 0.0, 150.0, speed=1000.0), 0.0)  # 155 mm at 1000 mm/min: 9.3 s
    now, gaps = FRAME_S, []
    for move in _zigzag(150):
        when = s.next_write_time(now, move)
        gaps.append(when - now)
        s.wrote(move, when)
        assert s.waiting_seconds(when) <= 1.0 + 1e-9
        now = s.wire_free_s
    assert max(gaps) > 5.0  # the line waited for the long move to near its end
