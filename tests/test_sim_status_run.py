"""The simulator's quiet stretches read as runs (issue 11: a 20-minute virtual job in ≤ 0.5 s).

``SimulatedArm.status_run`` times the steps a virtual-time host would take ahead, ``status_frame``
builds a step's frame and ``commit_status_run`` makes the steps read so: the same frames at the
same clock times, to the last bit, as ``Serial.next_event_s`` and ``advance_to`` taking them one
by one.  The status encoder builds a pose kind on a path from ``Segment.cartesian_at``: the same floats as
``Segment.sample``.  tests/test_virtual_fidelity.py holds whole runs to their recorded digests.
"""

from __future__ import annotations

import math

from hypothesis import given, settings, strategies as st

from armctl.core.motion import MotionModel
from armctl.host.profile import default_profile
from armctl.core.protocol import ArcEnd, ArcStart, Delay, JointMove, LinearMove, StatusReader
from armctl.sim.model import SimOptions, SimulatedArm

MIN_STEP_S = 1e-6
JOB = [
    LinearMove(250, -40, 150, 180, 0, 0, 1500, 3000),
    LinearMove(250, 40, 160, 180, 0, 0, 1200, 600),
    Delay(200),
    ArcStart(240, 60, 170, 180, 0, 0, 1500, 40, 2400),
    ArcEnd(210, 80, 170, 180, 0, 0, 1500, 1200),
    JointMove(10, 20, 30, 0, 45, 0, 1500, 40),
]


def _arm() -> SimulatedArm:
    arm = SimulatedArm(SimOptions())
    for command in JOB:
        arm.write(command.encode(), 0.0)
    return arm


def _by_steps(end_s: float) -> list[tuple[float, bytes]]:
    """``next_event_s`` and ``advance_to``'s arithmetic, one burst at a time (model time = clock time)."""
    arm, now, read = _arm(), 0.0, []
    while now < end_s:
        now = now + max(max(0.0, arm.next_output_time() - now), MIN_STEP_S)
        data = arm.advance(now)
        if data:
            read.append((now, data))
    return read


def _by_runs(end_s: float, run_frames: int, read_of_each: int | None = None) -> tuple[list[tuple[float, bytes]], int]:
    """The same, reading quiet stretches as runs (only ``read_of_each`` of each run when given:
    the host stopped at a frame that was news); the steps read from runs too."""
    arm, now, read, from_runs = _arm(), 0.0, [], 0
    while now < end_s:
        run = arm.status_run(now, end_s, MIN_STEP_S, run_frames, 0.0, 1.0)
        if run:
            used = len(run) if read_of_each is None else min(len(run), read_of_each)
            built = arm.status_frames(run[:used])  # the link's way: a batch at a time
            assert built == [arm.status_frame(kind, due_s) for _, kind, due_s, _, _ in run[:used]]
            read += [(step[0], data) for step, data in zip(run, built)]
            arm.commit_status_run(run, used)
            now, from_runs = run[used - 1][0], from_runs + used
            continue
        now = now + max(max(0.0, arm.next_output_time() - now), MIN_STEP_S)
        data = arm.advance(now)
        if data:
            read.append((now, data))
    return read, from_runs


def test_runs_read_what_the_steps_read():
    end_s = 40.0
    expected = _by_steps(end_s)
    assert len(expected) > 1000
    for run_frames, read_of_each in ((512, None), (8, None), (7, 3), (1, 1)):
        got, from_runs = _by_runs(end_s, run_frames, read_of_each)
        assert got == expected, (run_frames, read_of_each)
        assert from_runs > 0.9 * len(expected)  # the quiet stretches were read as runs
        assert all(len(frame) == 9 for _, frame in got)


def test_no_run_across_an_event_or_with_faults():
    arm = _arm()
    assert arm.status_run(0.0, None, MIN_STEP_S, 10, 0.0, 1.0) == []  # the first status frame is in flight
    assert arm.advance(0.01)  # it has arrived
    run = arm.status_run(0.01, None, MIN_STEP_S, 10_000, 0.0, 1.0)
    landing_s = arm._landings[0][0]
    assert run and run[-1][0] < landing_s < run[-1][0] + 0.03  # stops before the first frame lands
    assert arm.status_run(0.01, 0.02, MIN_STEP_S, 10, 0.0, 1.0) == []  # no frame arrives by end_s
    noisy = SimulatedArm(SimOptions(noise_rate=0.1, seed=1))
    noisy.advance(0.01)
    assert noisy.status_run(0.01, None, MIN_STEP_S, 10, 0.0, 1.0) == []


def test_decode_frame_is_what_feed_finds():
    arm = _arm()
    frames = [data for _, data in _by_steps(5.0)]
    bulk, single = StatusReader(), StatusReader()
    assert [bulk.decode_frame(data) for data in frames] == [single.feed(data)[0] for data in frames]
    assert bulk.decode_frame(b"\x00" * 9) is None
    held = StatusReader()
    held.feed(frames[0][:4])
    assert held.decode_frame(frames[1]) is None  # bytes held from before: feed's job
    # a batch: decode_frame of each, up to the first that is not a frame
    assert StatusReader().decode_frames(frames) == [single.decode_frame(data) for data in frames]
    assert StatusReader().decode_frames(frames[:7] + [b"\x00" * 9] + frames[8:]) == [single.decode_frame(data) for data in frames[:7]]
    assert StatusReader().decode_frames(frames[:3] + [frames[3][:8]]) == [single.decode_frame(data) for data in frames[:3]]
    assert held.decode_frames(frames[1:]) == []
    del arm


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=-0.1, max_value=1.1))
def test_cartesian_at_is_sample(fraction):
    model = MotionModel(default_profile())
    pose, arc = model.initial_pose(), None
    checked = 0
    for command in JOB:
        if isinstance(command, ArcStart):
            arc = command
            continue
        segment = model.plan(command, pose, arc_start=arc) if arc else model.plan(command, pose)
        arc, pose = None, segment.end
        if not hasattr(segment, "cartesian_at"):
            continue
        t_s = fraction * segment.duration_s
        values = segment.cartesian_at(t_s)
        sampled = segment.sample(t_s)
        if values is None:
            assert sampled is segment.start or sampled is segment.end
        else:
            assert values == tuple(sampled.cartesian)
            assert all(math.copysign(1, a) == math.copysign(1, b) for a, b in zip(values, sampled.cartesian))
            assert sampled.ik_hint == segment.end.ik_hint and sampled.pwm_us == segment.end.pwm_us
        checked += 1
    assert checked >= 3  # two lines and the arc


def _link_reads(raise_at: int | None, until_s: float, as_run: bool = False) -> list[tuple[int, float]]:
    """What a virtual link's waits read up to ``until_s`` when the frames' receiver raises (a
    Ctrl-C) at frame ``raise_at`` and the waits go on after it: ``on_status`` one burst at a time,
    or (``as_run``) a wait's ``news`` that takes the frames of runs a batch at a time and raises
    after taking the batch that holds frame ``raise_at`` — in the middle of a run (all its
    frames count as read)."""
    from armctl.host.link import Link

    seen: list[tuple[int, float]] = []
    batches = []

    def on_status(frame, now):
        seen.append((frame.KIND, now))
        if len(seen) == raise_at:
            raise KeyboardInterrupt
        return False

    def on_status_run(frames, times):
        before = len(seen)
        batches.append(len(frames))
        seen.extend((frame.KIND, now) for frame, now in zip(frames, times))
        if raise_at is not None and before < raise_at <= len(seen):
            raise KeyboardInterrupt
        return None

    with Link.open("sim://?clock=virtual", on_status=on_status) as link:
        while link.clock.now() < until_s:
            try:
                link.wait(until_s, on_status_run if as_run else None)
            except KeyboardInterrupt:
                pass
        assert link.reader.frames == len(seen) and link.bytes_received == 9 * len(seen)
        built = link.port.model.status_frames_built  # every frame built was read once, but one in flight
        assert built - len(seen) == (1 if link.port.model.arm_line.next_arrival_s() is not None else 0)
    assert max(batches, default=0) > 1 if as_run else not batches  # the runs' frames went as batches
    return seen


def test_a_run_cut_short_by_an_exception_reads_no_frame_twice():
    whole = _link_reads(None, 3.0)
    assert len(whole) == 100  # one per 30 ms
    for raise_at in (1, 37, 99):
        assert _link_reads(raise_at, 3.0) == whole
    assert _link_reads(None, 3.0, as_run=True) == whole  # the frames of runs in batches: the same
    for raise_at in (1, 37, 99):
        assert _link_reads(raise_at, 3.0, as_run=True) == whole
