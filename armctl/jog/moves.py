"""Step jog and gripper moves, built from the pose the arm reports; and how to see they arrived.

Strategy: pure functions of an ``ArmState`` snapshot and the profile.  ``reported_pose`` reads
the pose a still arm reports (X/Y/Z from status kind 0, joints from kinds 1–2, PWM from kind 4,
the attitude from the joints by forward kinematics — the status carries none).  A step is one
``LinearMove`` (linear mode: X, Y or Z ± the increment, attitude and PWM kept) or one
``JointMove`` (joint mode: one joint ± the increment, clamped to its limits) from that pose; a
gripper change is a ``JointMove`` to the reported joints with the new PWM, so the arm stays
where it is (a G1 to the reported X/Y/Z would go through IK from a 0.1 mm-rounded point).  Each
move comes with a ``Target``: the status kind that will show it done and the values it must
show.  A step that cannot be made is a ``Refused`` with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.armstate import ArmState
from ..core.kinematics import reach_problem
from ..core.protocol import (
    PWM_RANGE_US, JointMove, JointsHighStatus, JointsLowStatus, LinearMove, PauseStatus, PositionStatus,
)
from .keymap import JogAxis

ARRIVAL_MM = 0.25  # reported X/Y/Z within this of the target: arrived (status resolution 0.1 mm)
ARRIVAL_DEG = 0.05  # reported joints within this (status resolution 0.01 deg)
ARRIVAL_US = 1.0
POSE_KINDS = (PositionStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND, PauseStatus.KIND)


class Refused(Exception):
    """A step or gripper move that cannot be sent; the message says why."""


@dataclass(frozen=True)
class Reported:
    """A pose as the status reports it: X/Y/Z in the worktable frame, attitude by FK."""

    xyz_mm: tuple[float, float, float]
    attitude_deg: tuple[float, float, float]  # B0, B1, W (script letters A, B, C)
    joints_deg: tuple[float, ...]
    pwm_us: float
    origin_mm: tuple[float, float, float]


@dataclass(frozen=True)
class Target:
    """Status ``kind`` shows ``values`` (within ``tolerance``) once the move is done."""

    kind: int
    values: tuple[float, ...]
    tolerance: float

    def reached(self, state: ArmState, since_s: float) -> bool:
        seen = state.last_seen.get(self.kind)
        if seen is None or seen < since_s:
            return False
        reported = _kind_values(state, self.kind)
        if any(v is None for v in reported):
            return False
        return max(abs(a - b) for a, b in zip(reported, self.values)) <= self.tolerance


def _kind_values(state: ArmState, kind: int) -> tuple:
    if kind == PositionStatus.KIND:
        return (state.x_mm, state.y_mm, state.z_mm)
    if kind == JointsLowStatus.KIND:
        return tuple(state.joints_deg[0:3])
    if kind == JointsHighStatus.KIND:
        return tuple(state.joints_deg[3:6])
    if kind == PauseStatus.KIND:
        return (state.pwm_us,)
    raise ValueError(f"status kind {kind} carries no pose")


def fresh(state: ArmState, since_s: float, kinds=POSE_KINDS) -> bool:
    """Every one of ``kinds`` was reported at or after ``since_s``."""
    return all(state.last_seen.get(kind, float("-inf")) >= since_s for kind in kinds)


def reported_pose(state: ArmState, kinematics) -> Reported | None:
    """The reported pose, or None while a part of it has not been reported."""
    joints = tuple(state.joints_deg)
    if state.x_mm is None or any(j is None for j in joints) or state.pwm_us is None:
        return None
    attitude = tuple(kinematics.forward(joints)[3:6])
    origin = tuple(v if v is not None else 0.0 for v in state.worktable_mm)
    return Reported((state.x_mm, state.y_mm, state.z_mm), attitude, joints, float(state.pwm_us), origin)


def _pwm(reported: Reported) -> float:
    low, high = PWM_RANGE_US
    if not low <= reported.pwm_us <= high:
        raise Refused(f"the arm reports PWM {reported.pwm_us:g} µs, outside {low:g}…{high:g}: "
                      "open or close the gripper first")
    return reported.pwm_us


def step_move(jog: JogAxis, size: float, reported: Reported, speed: float,
              profile) -> tuple[LinearMove | JointMove, Target]:
    """One step of ``size`` mm or degrees along ``jog`` from ``reported``, at ``speed``
    (mm/min for a linear step, deg/s for a joint step)."""
    if jog.is_linear:
        xyz = list(reported.xyz_mm)
        xyz[jog.index] += jog.sign * size
        pose = (*xyz, *reported.attitude_deg)
        problem = reach_problem(pose, profile, reported.origin_mm, near=reported.joints_deg)
        if problem is not None:
            raise Refused(f"{jog.label} {size:g} mm: {problem}")
        command = LinearMove(*pose, pwm_us=_pwm(reported), speed_mm_min=speed)
        return command, Target(PositionStatus.KIND, (command.x_mm, command.y_mm, command.z_mm), ARRIVAL_MM)
    joints = list(reported.joints_deg)
    low, high = profile.joint_limits_deg[jog.axis]
    wanted = joints[jog.axis] + jog.sign * size
    clamped = min(high, max(low, wanted))
    if abs(clamped - joints[jog.axis]) < 0.005:
        raise Refused(f"{jog.label}: joint {jog.axis + 1} is at its limit ({low:g}…{high:g} deg)")
    joints[jog.axis] = clamped
    command = JointMove(*joints, pwm_us=_pwm(reported), speed_deg_s=speed)
    kind = JointsLowStatus.KIND if jog.axis < 3 else JointsHighStatus.KIND
    first = 0 if jog.axis < 3 else 3
    return command, Target(kind, tuple(command.joints_deg[first : first + 3]), ARRIVAL_DEG)


def gripper_move(pwm_us: float, reported: Reported, speed_deg_s: float) -> tuple[JointMove, Target]:
    """The gripper to ``pwm_us`` without moving the arm: a joint move to the reported joints."""
    command = JointMove(*reported.joints_deg, pwm_us=pwm_us, speed_deg_s=speed_deg_s)
    return command, Target(PauseStatus.KIND, (command.pwm_us,), ARRIVAL_US)
