"""``ArmState.update_many`` (how ``Link`` merges the frames of its virtual runs when the state is
read) leaves the state one ``update`` a frame leaves — H9's hold-back of jumps included — and a
virtual link's state, read after a job's waits, is the state of every frame it read."""

from __future__ import annotations

import copy

from hypothesis import given, settings, strategies as st

from armctl.core.armstate import ArmState
from armctl.host.link import Link
from test_link_news import news_of
from armctl.core.protocol import (
    FileLengthStatus, FileStatus, JointsHighStatus, JointsLowStatus, PauseStatus, PositionStatus, RunPositionStatus,
    WorktableStatus, WristStatus,
)

# few distinct values, far apart: jumps (held, then confirmed or not) are common
_mm = st.sampled_from([0.0, 0.5, 100.0, -250.0])
_deg = st.sampled_from([0.0, 0.25, 90.0, -170.0])
frames = st.one_of(
    st.builds(PositionStatus, _mm, _mm, _mm),
    st.builds(JointsLowStatus, _deg, _deg, _deg),
    st.builds(JointsHighStatus, _deg, _deg, _deg),
    st.builds(WorktableStatus, _mm, _mm, _mm),
    st.builds(PauseStatus, st.sampled_from([0, 1]), st.sampled_from([0, 1500])),
    st.builds(WristStatus, _deg, _deg),
    st.builds(FileLengthStatus, st.sampled_from([0.0, 10.0])),
    st.builds(FileStatus, st.sampled_from([0, 7])),
    st.builds(RunPositionStatus, st.sampled_from([0.0, 3.0])),
)


def _everything(state: ArmState) -> tuple:
    return (state.to_json(), dict(state.last_seen), state.frames, state.suspect_frames, dict(state._held))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(frames, st.floats(0.0, 0.5)), max_size=60), st.lists(st.integers(0, 60), max_size=4),
       st.sampled_from([None, 100.0]))
def test_merging_frames_in_batches_is_updating_frame_by_frame(steps, cuts, max_speed):
    one_by_one = ArmState(max_speed_mm_s=max_speed, max_joint_speed_deg_s=max_speed)
    merged = copy.deepcopy(one_by_one)
    read, now = [], 0.0
    for frame, gap_s in steps:
        now += gap_s
        read.append((frame, now))
        one_by_one.update(frame, now)
    bounds = sorted({0, len(read), *(min(c, len(read)) for c in cuts)})
    for start, end in zip(bounds, bounds[1:]):
        merged.update_many(read[start:end])
    assert _everything(merged) == _everything(one_by_one)


def test_a_virtual_links_state_is_every_frame_it_read_merged():
    seen = []

    def on_status(frame, now):
        seen.append((frame, now))
        return len(seen) % 50 == 0  # news now and then: the link runs on past the rest

    reference = ArmState(max_speed_mm_s=100.0, max_joint_speed_deg_s=90.0)
    news = news_of(on_status)
    link = Link.open("sim://?clock=virtual", state=copy.deepcopy(reference))
    with link:
        for _ in range(3):
            link.wait(None, news)
        state = link.snapshot()[0]
        for _ in range(100):  # more than a merge holds (UNMERGED_FRAMES_MAX): merged on the way
            link.wait(None, news)
        later = link.state
    assert len(seen) == 103 * 50
    for frame, now in seen[:150]:
        reference.update(frame, now)
    assert _everything(state) == _everything(reference)
    for frame, now in seen[150:]:
        reference.update(frame, now)
    assert _everything(later) == _everything(reference)
