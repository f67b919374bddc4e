"""The simulated arm in virtual time: the line, the connector (H6, H7), execution times from
the shared motion model, and the status output."""

from __future__ import annotations

import pytest

from armctl.core.motion import MotionModel, Planner
from armctl.host.profile import default_profile
from armctl.core.protocol import (
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    AccelLinearMove,
    ArcEnd,
    ArcStart,
    Delay,
    JointMove,
    LinearMove,
    MCode,
    PositionStatus,
    StatusReader,
    byte_seconds,
    frame_seconds,
)
from armctl.sim.model import SimOptions, SimulatedArm

FRAME_S = frame_seconds(9600)  # 50 ms
LONG_DELAY = Delay(100_000)  # holds the arm far longer than any test fills the buffer


def write_all(arm, commands, now_s=0.0):
    arm.write(b"".join(c.encode() for c in commands), now_s)


# --- the line and the FIFO ------------------------------------------------------------------------


def test_frames_land_50_ms_apart_at_9600_baud():
    arm = SimulatedArm()
    write_all(arm, [LONG_DELAY] * 3, now_s=1.0)
    arm.advance(2.0)
    assert [f.arrival_s for f in arm.frames_received] == pytest.approx([1.05, 1.10, 1.15])
    assert FRAME_S == pytest.approx(0.05)


def test_a_later_write_queues_behind_bytes_still_on_the_wire():
    arm = SimulatedArm()
    write_all(arm, [LONG_DELAY], now_s=0.0)
    write_all(arm, [LONG_DELAY], now_s=0.01)  # the first frame still occupies the line
    assert arm.host_bytes_in_flight(0.01) == 96 - 9  # 9.6 byte times have passed
    arm.advance(1.0)
    assert [f.arrival_s for f in arm.frames_received] == pytest.approx([0.05, 0.10])


def test_time_never_runs_backwards():
    arm = SimulatedArm()
    arm.advance(2.0)
    write_all(arm, [MCode(1)], now_s=1.0)  # taken as written at 2.0
    assert arm.advance(1.5) == b""
    arm.advance(3.0)
    assert arm.frames_received[0].arrival_s == pytest.approx(2.05)


def test_the_baud_rate_sets_the_frame_time():
    arm = SimulatedArm(SimOptions(baud=115200))
    write_all(arm, [LONG_DELAY] * 2)
    arm.advance(1.0)
    assert [f.arrival_s for f in arm.frames_received] == pytest.approx([480 / 115200, 960 / 115200])


@pytest.mark.parametrize("fifo_frames", [50, 200])
def test_overflow_at_exactly_one_frame_more_than_fifo_frames_behind_the_executing_one(fifo_frames):
    arm = SimulatedArm(SimOptions(fifo_frames=fifo_frames))
    write_all(arm, [LONG_DELAY] * (fifo_frames + 1))  # the first runs, fifo_frames wait behind it
    arm.advance((fifo_frames + 2) * FRAME_S - 0.001)
    assert arm.frames_dropped == 0 and arm.fifo_occupancy == fifo_frames
    write_all(arm, [LONG_DELAY], now_s=arm.now_s)
    arm.advance(20.0)
    assert arm.frames_dropped == 1
    assert arm.dropped_indexes == [fifo_frames + 1]
    assert [f.accepted for f in arm.frames_received] == [True] * (fifo_frames + 1) + [False]
    assert arm.peak_fifo_occupancy == fifo_frames


def test_the_slot_frees_when_the_first_frame_finishes():
    arm = SimulatedArm()
    write_all(arm, [Delay(9_000)] + [LONG_DELAY] * 201)  # the first ends at 9.05 s, the 202nd lands at 10.1 s
    arm.advance(20.0)
    assert arm.frames_dropped == 0 and arm.fifo_occupancy == 200


def test_h6_frames_landing_while_full_are_dropped_whole_and_later_frames_are_intact():
    arm = SimulatedArm()
    write_all(arm, [Delay(12_000)] + [Delay(1)] * 200 + [MCode(7), MCode(8), MCode(9)])
    arm.advance(11.0)
    assert arm.dropped_indexes == [201, 202, 203]
    late = LinearMove(200, 10, 250, 180, 0, 0, 1500, 3000)
    write_all(arm, [late], now_s=13.0)
    arm.advance_until_idle()
    assert arm.frames_received[-1].index == 204 and arm.frames_received[-1].command == late
    assert arm.execution_log[-1].command == late and arm.execution_log[-1].outcome == "done"
    assert arm.bad_frames == 0


def test_h7_a_bad_tail_discards_the_frame_and_the_connector_resyncs_after_junk():
    arm = SimulatedArm()
    good = MCode(3)
    bad = bytearray(MCode(4).encode())
    bad[-1] = 0x00
    arm.write(b"\x01\x02\x03" + bytes(bad) + b"junk" + good.encode(), 0.0)
    arm.advance(1.0)
    assert arm.bad_frames == 1
    assert arm.skipped_bytes == 3 + 4
    assert [f.command for f in arm.frames_received] == [good]
    assert arm.frames_received[0].arrival_s == pytest.approx((3 + 48 + 4 + 48) * byte_seconds(9600))


def test_h7_a_head_byte_inside_junk_swallows_the_next_48_bytes():
    arm = SimulatedArm()
    arm.write(b"\xee" + MCode(1).encode() + MCode(2).encode(), 0.0)
    arm.advance(1.0)
    # 0xEE + 47 bytes of MCode(1) end with MCode(1)'s 47th byte, not a tail: discarded;
    # the connector then hunts from MCode(1)'s tail byte (0xEF, not a head) to MCode(2).
    assert arm.bad_frames == 1
    assert [f.command for f in arm.frames_received] == [MCode(2)]


# --- execution times ---------------------------------------------------------------------------------

JOB = [
    LinearMove(200, 0, 200, 180, 0, 0, 1500, 3000),
    AccelLinearMove(0, 250, 50, 200, 180, 0, 0, 800, 4000),
    AccelLinearMove(1, 250, -50, 200, 180, 0, 0, 800, 4000),
    AccelLinearMove(2, 200, -50, 250, 180, 0, 0, 500, 3000, speed0_mm_min=600),
    AccelLinearMove(0, 200, 0, 250, 180, 0, 0, -600, 2000),
    JointMove(10, 20, 30, 0, 40, 0, 1500, 60, smoothing=3),
    JointMove(0, 0, 0, 0, 90, 0, 2000, 90),
    Delay(250),
    MCode(3),
    ArcStart(240, 30, 300, 180, 0, 0, 2000, 40, 2400),
    ArcEnd(210, 60, 300, 180, 0, 0, 2000, 1200),
    LinearMove(210, 60, 300, 180, 0, 0, 1000, 3000),  # PWM only
]


@pytest.mark.parametrize("speed_factor", [1.0, 1.3, 0.7])
def test_durations_are_the_motion_models_at_the_speed_factor(speed_factor):
    arm = SimulatedArm(SimOptions(speed_factor=speed_factor))
    write_all(arm, JOB)
    arm.advance_until_idle()
    planner = Planner(MotionModel(default_profile(), speed_factor))
    segments = planner.feed_all(JOB)
    expected = [s.duration_s for s in segments]
    expected[9] = segments[10].duration_s  # the G300 runs with its G301, as one arc
    log = arm.execution_log
    assert [e.command for e in log] == JOB
    assert [e.outcome for e in log] == ["done"] * len(JOB)
    assert [e.duration_s for e in log] == pytest.approx(expected, abs=1e-9)
    # back to back: each starts when the previous ends (every frame landed long before)
    for before, after in zip(log[:-1], log[1:]):
        if after.index != 10:  # the G301 starts with its G300
            assert after.start_s == pytest.approx(max(before.end_s, arm.frames_received[after.index].arrival_s))
    assert arm.pose.isclose(planner.pose, mm=1e-6, deg=1e-6)


def test_speed_factor_slows_moves_but_not_delays():
    slow = SimulatedArm(SimOptions(speed_factor=1.3))
    write_all(slow, [JOB[0], Delay(500)])
    slow.advance_until_idle()
    fast = SimulatedArm()
    write_all(fast, [JOB[0], Delay(500)])
    fast.advance_until_idle()
    assert slow.execution_log[0].duration_s == pytest.approx(1.3 * fast.execution_log[0].duration_s)
    assert slow.execution_log[1].duration_s == pytest.approx(0.5)


def test_next_event_time_lets_a_driver_jump_between_events():
    arm = SimulatedArm()
    write_all(arm, [Delay(100)])
    times = []
    while arm.now_s < 0.2:
        times.append(arm.next_event_time())
        arm.advance(times[-1])
    assert times == sorted(times)
    assert any(t == pytest.approx(0.05) for t in times)  # the frame lands
    assert any(t == pytest.approx(0.15) for t in times)  # the delay ends
    assert any(t == pytest.approx(0.03) for t in times)  # a status frame is built


# --- status output ---------------------------------------------------------------------------------


def test_status_frames_rotate_through_the_nine_kinds_every_30_ms():
    arm = SimulatedArm()
    byte_s = byte_seconds(9600)
    reader = StatusReader()
    seen = []
    for n in range(20):
        done_s = n * STATUS_PERIOD_S + 9 * byte_s  # frame n's last bit reaches the host
        assert reader.feed(arm.advance(done_s - 1e-6)) == []
        frames = reader.feed(arm.advance(done_s))
        assert len(frames) == 1
        seen.append(frames[0].KIND)
    assert seen == list(STATUS_ROTATION * 3)[:20]
    assert reader.skipped_bytes == 0


def test_status_reports_the_position_interpolated_mid_move():
    arm = SimulatedArm()
    start = arm.pose.cartesian
    move = LinearMove(start.x_mm, start.y_mm, start.z_mm - 100, *start[3:], 1500, 600)  # 10 mm/s
    write_all(arm, [move])
    reader = StatusReader()
    frames = reader.feed(arm.advance(9.0))
    positions = [f for f in frames if isinstance(f, PositionStatus)]
    assert len(positions) == 34
    for k, frame in enumerate(positions):
        built_s = 9 * k * STATUS_PERIOD_S
        expected_z = start.z_mm - 10.0 * max(0.0, built_s - FRAME_S)
        assert frame.z_mm == pytest.approx(expected_z, abs=0.051)
        assert frame.x_mm == pytest.approx(start.x_mm, abs=0.051)


def test_status_reports_joints_pause_pwm_and_origin():
    arm = SimulatedArm()
    write_all(arm, [JointMove(10, 20, 30, 5, 40, 6, 2100, 120)])
    arm.advance_until_idle()
    frames = {f.KIND: f for f in StatusReader().feed(arm.advance(arm.now_s + 0.3))}
    assert (frames[1].j1_deg, frames[1].j2_deg, frames[1].j3_deg) == (10, 20, 30)
    assert (frames[2].j4_deg, frames[2].j5_deg, frames[2].j6_deg) == (5, 40, 6)
    assert (frames[5].w0_deg, frames[5].w1_deg) == (5, 40)
    assert frames[4].pwm_us == 2100 and not frames[4].paused
    assert frames[3].fields() == {"x_mm": 0, "y_mm": 0, "z_mm": 0}


# --- faults ----------------------------------------------------------------------------------------


def _status_bytes(**options):
    arm = SimulatedArm(SimOptions(**options))
    return arm, arm.advance(59.99)  # 2000 status frames, the last one fully arrived


def test_faults_on_the_status_line_are_deterministic_for_a_seed():
    options = dict(status_loss_rate=0.05, status_corrupt_rate=0.05, noise_rate=0.05, seed=7)
    assert _status_bytes(**options)[1] == _status_bytes(**options)[1]
    assert _status_bytes(**options)[1] != _status_bytes(**{**options, "seed": 8})[1]


@pytest.mark.parametrize(
    "option, counter",
    [("status_loss_rate", "frames_lost"), ("status_corrupt_rate", "frames_corrupted"), ("noise_rate", "noise_bytes")],
)
def test_each_fault_happens_at_its_rate(option, counter):
    clean_arm, clean = _status_bytes()
    arm, data = _status_bytes(**{option: 0.05, "seed": 3})
    count = getattr(arm.faults.counts, counter)
    frames = arm.status_frames_built
    assert frames == 2000
    if counter == "noise_bytes":
        assert 0.05 * frames * 0.5 <= count <= 0.05 * frames * 4 * 1.5
        assert len(data) == len(clean) + count
    else:
        assert 0.03 * frames <= count <= 0.07 * frames
    decoded = StatusReader().feed(data)
    if counter == "frames_lost":
        assert len(decoded) == frames - count
    assert len(decoded) >= frames - count - 20  # the reader resynchronises after every fault
