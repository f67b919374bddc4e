"""The simulator's small pure parts on their own: the wire, the H7 framer, the H6 FIFO, the
status schedule and the seeded faults."""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from armctl.errors import FieldError
from armctl.core.protocol import (
    STATUS_ROTATION,
    Delay,
    JointsHighStatus,
    JointsLowStatus,
    PositionStatus,
    WorktableStatus,
    WristStatus,
    LinearMove,
    PauseToggle,
    StatusReader,
    decode_status,
    frame_seconds,
)
from armctl.sim.connector import Connector, Framer, decode_received
from armctl.sim.faults import StatusFaults
from armctl.sim.model import SimulatedArm
from armctl.sim.status import ArmSnapshot, StatusSchedule, build_status, status_bytes
from armctl.sim.wire import Wire

MOVE = LinearMove(200, 0, 150, 0, 0, 0, 1500, 3000).encode()
PAUSE = PauseToggle().encode()


# --- the wire ----------------------------------------------------------------------------------


def test_a_frame_takes_50_ms_at_9600_baud_and_queues_behind_the_previous_one():
    wire = Wire(9600)
    first = wire.send(MOVE, 1.0)
    second = wire.send(MOVE, 1.0)
    assert first == 1.0
    assert second == pytest.approx(1.0 + frame_seconds(9600))
    assert wire.arrival_s(second, 47) == pytest.approx(1.1)


def test_bytes_arrive_one_byte_time_apart_and_are_taken_once():
    wire = Wire(9600)
    wire.send(b"abcdef", 0.0)
    assert wire.take(0.0) == b""
    assert wire.take(2.5 / 960) == b"ab"
    assert wire.next_arrival_s() == pytest.approx(3 / 960)
    assert wire.in_flight(2.5 / 960) == 4
    assert wire.take(1.0) == b"cdef"
    assert wire.next_arrival_s() is None and wire.in_flight(1.0) == 0


def test_an_idle_line_starts_a_write_at_once():
    wire = Wire(9600)
    wire.send(b"x", 0.0)
    assert wire.send(b"y", 5.0) == 5.0


# --- H7 framing ----------------------------------------------------------------------------------


def test_framer_reports_the_offset_of_each_frames_last_byte():
    framer = Framer()
    found = framer.feed(MOVE + PAUSE)
    assert [end for end, _ in found] == [47, 95]
    assert [frame for _, frame in found] == [MOVE, PAUSE]


def test_framer_completes_a_frame_fed_byte_by_byte():
    framer = Framer()
    ends = []
    for k, byte in enumerate(MOVE):
        ends += [(k, end, frame) for end, frame in framer.feed(bytes([byte]))]
    assert ends == [(47, 0, MOVE)]


def test_h7_bad_tail_discards_48_bytes_and_junk_is_skipped():
    framer = Framer()
    bad = MOVE[:-1] + b"\x00"
    found = framer.feed(b"\x01\x02" + bad + b"\x33" + MOVE)
    assert [frame for _, frame in found] == [None, MOVE]
    assert framer.bad_frames == 1
    assert framer.skipped_bytes == 3


# --- H6 FIFO -----------------------------------------------------------------------------------


def _frame(index):
    return decode_received(index, 0.0, Delay(1000).encode())


def test_capacity_counts_the_frames_waiting_behind_the_one_executing():
    connector = Connector()  # the document's 200 (fifo_frames: H6's readings are this one number)
    assert all(connector.land(_frame(k)) for k in range(200))
    assert connector.land(_frame(200)) is False  # nothing taken yet: 200 wait, the 201st is dropped
    executing = connector.take()  # the arm takes one: a slot frees for the frames behind it
    assert connector.land(_frame(201)) is True
    assert connector.land(_frame(202)) is False
    assert connector.dropped_indexes == [200, 202]
    connector.finish(executing)
    assert connector.peak_occupancy == 200


def test_a_smaller_fifo():
    connector = Connector(capacity_frames=50)
    assert [connector.land(_frame(k)) for k in range(51)] == [True] * 50 + [False]


def test_undecodable_frames_still_take_a_slot():
    frame = bytearray(MOVE)
    frame[1] = ord("9")  # no command '9'
    received = decode_received(0, 0.0, bytes(frame))
    assert received.command is None and "unknown motion command" in received.error


# --- status ------------------------------------------------------------------------------------

SNAPSHOT = ArmSnapshot((12.3, -4.5, 99999.0), (1, 2, 3, 4, 5, 6), (0, 0, 0), True, 1500, 2048, 1, 512)


def test_the_schedule_rotates_through_the_nine_kinds_every_30_ms():
    schedule = StatusSchedule()
    kinds, times = [], []
    for _ in range(18):
        times.append(schedule.next_s)
        kinds.append(schedule.pop())
    assert tuple(kinds) == STATUS_ROTATION * 2
    assert times[9] == pytest.approx(0.27)


def test_every_kind_builds_and_out_of_range_values_are_clamped():
    frames = [build_status(kind, SNAPSHOT) for kind in STATUS_ROTATION]
    assert [decode_status(f.encode()) for f in frames] == frames
    assert frames[0].z_mm == pytest.approx(3276.7)
    assert frames[4].paused and frames[4].pwm_us == 1500
    assert frames[5].fields() == {"w0_deg": 4.0, "w1_deg": 5.0}


_VALUE = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-400, 400), st.integers(-40000, 40000),
                   st.sampled_from([3276.75, -3276.75, 327.675, -327.675, 0.005, -0.005, 0.05, -0.05]))


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([PositionStatus, JointsLowStatus, JointsHighStatus, WorktableStatus, WristStatus]),
       st.lists(_VALUE, min_size=3, max_size=3))
def test_encode_values_is_the_frames_encoding_bytes_and_errors_alike(frame_class, values):
    values = values[: len(frame_class._field_names())]
    try:
        expected = frame_class(*values).encode()
    except FieldError as error:
        with pytest.raises(FieldError) as raised:
            frame_class.encode_values(*values)
        assert str(raised.value) == str(error)
    else:
        assert frame_class.encode_values(*values) == expected


@settings(max_examples=200, deadline=None)
@given(st.tuples(*[_VALUE] * 3), st.tuples(*[_VALUE] * 6), st.tuples(*[_VALUE] * 3), st.booleans(), _VALUE)
def test_status_bytes_are_build_status_encoded(position, joints, origin, paused, pwm):
    assume(all(isinstance(v, int) or math.isfinite(v) for v in (*position, *joints, *origin, pwm)))
    snapshot = dataclasses.replace(SNAPSHOT, position_mm=position, joints_deg=joints, origin_mm=origin, paused=paused,
                                   pwm_us=pwm)
    for kind in STATUS_ROTATION:
        assert status_bytes(kind, snapshot) == build_status(kind, snapshot).encode()


def _run_faults(seed, count=4000, **rates):
    faults = StatusFaults(seed=seed, **rates)
    clean = build_status(0, SNAPSHOT).encode()
    stream = b"".join(faults.apply(clean) for _ in range(count))
    return faults, stream


def test_faults_are_deterministic_for_a_seed():
    assert _run_faults(7, loss_rate=0.1, corrupt_rate=0.1, noise_rate=0.1)[1] == _run_faults(
        7, loss_rate=0.1, corrupt_rate=0.1, noise_rate=0.1
    )[1]
    assert _run_faults(7, loss_rate=0.1)[1] != _run_faults(8, loss_rate=0.1)[1]


def test_status_frames_are_lost_at_the_rate():
    faults, stream = _run_faults(1, loss_rate=0.05)
    assert 150 <= faults.counts.frames_lost <= 250
    assert len(StatusReader().feed(stream)) == 4000 - faults.counts.frames_lost


def test_status_frames_are_corrupted_at_the_rate():
    faults, stream = _run_faults(2, corrupt_rate=0.05)
    assert 150 <= faults.counts.frames_corrupted <= 250
    assert len(stream) == 4000 * 9
    intact = stream.count(build_status(0, SNAPSHOT).encode())
    assert intact == 4000 - faults.counts.frames_corrupted


def test_noise_is_inserted_at_the_rate_and_the_reader_recovers():
    faults, stream = _run_faults(3, noise_rate=0.05)
    assert len(stream) == 4000 * 9 + faults.counts.noise_bytes
    assert 150 * 1 <= faults.counts.noise_bytes <= 250 * 4
    reader = StatusReader()
    assert len(reader.feed(stream)) >= 4000 - 10  # noise may look like a frame's head now and then


# --- properties ----------------------------------------------------------------------------------

_PIECES = st.lists(
    st.one_of(st.just(MOVE), st.just(PAUSE), st.just(Delay(5).encode()), st.binary(max_size=60)), max_size=12
)


@settings(max_examples=60, deadline=None)
@given(pieces=_PIECES, cuts=st.lists(st.integers(min_value=0, max_value=600), max_size=8))
def test_any_bytes_in_any_chunks_frame_the_same_and_never_raise(pieces, cuts):
    stream = b"".join(pieces)
    whole, chunked = SimulatedArm(), SimulatedArm()
    whole.write(stream, 0.0)
    edges = sorted({0, len(stream), *(c for c in cuts if c < len(stream))})
    for start, end in zip(edges[:-1], edges[1:]):
        chunked.write(stream[start:end], 0.0)
    whole.advance(1.0)  # at most 720 bytes: all landed by 0.75 s
    chunked.advance(1.0)
    assert [(f.raw, round(f.arrival_s, 9)) for f in whole.frames_received] == [
        (f.raw, round(f.arrival_s, 9)) for f in chunked.frames_received
    ]
    assert (whole.bad_frames, whole.skipped_bytes) == (chunked.bad_frames, chunked.skipped_bytes)
