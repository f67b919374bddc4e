"""The simulator's status encoder (armctl/sim/status.py ``StatusEncoder``) builds the very bytes
``status_bytes(kind, executor.snapshot(at_s))`` builds — for every kind, at rest and on every
kind of path, at any instant, with wild values clamped alike — and its reuse of the bytes of
the seldom-changing kinds never serves stale bytes."""

from __future__ import annotations

from hypothesis import given, settings, strategies as st

from armctl.core.protocol import (GoToPose, JointMove, LinearMove, PauseToggle, RunProgram, STATUS_ROTATION,
                             SetWorktableOrigin)
from armctl.sim.model import SimOptions, SimulatedArm
from armctl.sim.status import StatusEncoder, status_bytes

KINDS = st.sampled_from(STATUS_ROTATION)


def _arm(commands, robot_xyz: bool = False) -> SimulatedArm:
    arm = SimulatedArm(SimOptions(status_xyz_frame="robot" if robot_xyz else "worktable"))
    for command in commands:
        arm.write(command.encode(), arm.now_s)
    return arm


def _agree(arm: SimulatedArm, times, kinds) -> None:
    encoder = StatusEncoder()
    for at_s, kind in zip(times, kinds):
        arm.advance(at_s)
        at_s = arm.now_s
        expected = status_bytes(kind, arm.executor.snapshot(at_s))
        assert encoder.encode(kind, arm.executor, at_s) == expected, (kind, at_s)


@settings(max_examples=60, deadline=None)
@given(x=st.floats(150, 300), y=st.floats(-150, 150), z=st.floats(50, 250), feed=st.floats(300, 6000),
       robot_xyz=st.booleans(), origin=st.tuples(*[st.floats(-5000, 5000)] * 3),
       steps=st.lists(st.tuples(st.floats(0.001, 1.5), KINDS), min_size=5, max_size=40))
def test_the_encoder_builds_the_bytes_status_bytes_builds(x, y, z, feed, robot_xyz, origin, steps):
    commands = [
        LinearMove(x, y, z, 180.0, 0.0, 0.0, 1500.0, feed),
        SetWorktableOrigin(*origin),  # far off: kind 0 and 3 words clamp
        JointMove(10.0, 20.0, -10.0, 30.0, 60.0, 90.0, 1200.0, 30.0),
        PauseToggle(), PauseToggle(),
        RunProgram(1),
        GoToPose(1),
    ]
    arm = _arm(commands, robot_xyz)
    times, kinds, t = [], [], 0.0
    for dt, kind in steps:
        t += dt
        times.append(t)
        kinds.append(kind)
    _agree(arm, times, kinds)


def test_the_reused_bytes_follow_each_change_of_value():
    arm = _arm([RunProgram(2), PauseToggle(), PauseToggle(), SetWorktableOrigin(1.0, -0.0, 0.0)])
    _agree(arm, [k * 0.05 for k in range(1, 2000)], [STATUS_ROTATION[k % 9] for k in range(1, 2000)])
