"""The estimate times a LinearMove without its segment (``Planner.feed_line``, issue 23): the
same seconds, path length and notes as planning every frame, to the bit."""

from __future__ import annotations

import dataclasses

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core.estimate import JobEstimator
from armctl.core.motion import MotionModel, Planner
from armctl.host.profile import default_profile
from armctl.core.protocol import LinearMove, RunProgram

from test_lint_fastpaths import _commands

PROFILE = default_profile()


class PlanningEstimator(JobEstimator):
    """The estimate as it was: every frame's segment planned (the reference)."""

    def add(self, command) -> float:
        segment = self.planner.feed(command)
        return self._count(command, segment.duration_s, segment.kind, segment.length, segment.note)


def _bits(estimate) -> str:
    return repr(dataclasses.astuple(estimate))  # repr tells -0.0 from 0.0 and every last bit


@settings(max_examples=150, deadline=None)
@given(st.lists(_commands(), min_size=1, max_size=25), st.sampled_from([None, 0.7, 1.3]),
       st.sampled_from([0.5, 2.0]))
def test_estimate_of_lines_without_segments_is_the_planned_one(batches, speed_factor, lead_s):
    model = MotionModel(PROFILE, speed_factor=speed_factor)
    fast, slow = JobEstimator(model, model.initial_pose(), lead_s), PlanningEstimator(model, model.initial_pose(), lead_s)
    for batch in batches:
        for command in batch:
            assert fast.add(command) == slow.add(command)
    assert _bits(fast.result) == _bits(slow.result)
    assert fast.planner.pose == slow.planner.pose
    assert fast.planner.pose.known_joints == slow.planner.pose.known_joints


@settings(max_examples=100, deadline=None)
@given(st.lists(_commands(), min_size=1, max_size=25))
def test_feed_line_is_the_segments_duration_and_length(batches):
    model = MotionModel(PROFILE)
    slow, fast = Planner(model), Planner(model)
    for batch in batches:
        for command in batch:
            segment = slow.feed(command)
            if type(command) is LinearMove:
                assert fast.feed_line(command) == (segment.duration_s, segment.length)
            else:
                fast.feed(command)
    assert fast.pose == slow.pose


def test_clamped_speed_and_sd_program_notes():
    model = MotionModel(PROFILE)
    limit = PROFILE.speed.max_linear_mm_min
    commands = [LinearMove(250.0, 0.0, 150.0, 180.0, 0.0, 0.0, pwm_us=1500.0, speed_mm_min=limit * 2),
                LinearMove(250.0, 10.0, 150.0, 180.0, 0.0, 0.0, pwm_us=1500.0, speed_mm_min=limit * 2), RunProgram(3)]
    fast, slow = JobEstimator(model, model.initial_pose()), PlanningEstimator(model, model.initial_pose())
    for command in commands:
        fast.add(command), slow.add(command)
    assert fast.result.notes == slow.result.notes
    assert len(fast.result.notes) == 3 and "clamped" in fast.result.notes[0]
    assert _bits(fast.result) == _bits(slow.result)
