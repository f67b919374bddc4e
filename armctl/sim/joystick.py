"""The analog joystick (control 30/7): continuous motion while a value is off-centre.

Strategy: the last value received per axis sets a *rate*; the pose at any later time is a
closed form of the pose when the rate last changed, so nothing steps on a timer:
- joint axis ``k`` (0…5): joint ``k+1`` turns at ``rate = (value − 128) / 127 ×
  max_joint_deg_s / speed_factor`` (the profile's joint speed cap), clamped at the joint's limits;
- linear axis 100: the tool point moves along X, Y, Z at ``(value − 128) / 127 ×
  max_linear_mm_min / 60 / speed_factor`` mm/s each, attitude kept; where the path leaves the arm's reach or
  its joint limits the tool stops at the last reachable point (found by bisection).
Values inside the still band 108…148 mean rate 0: the axis stops at once.  Full deflection
(0 or 255) is clamped to the cap.  Pure: the time is always an argument.
"""

from __future__ import annotations

from ..core.kinematics import Unreachable
from ..core.protocol import JOYSTICK_LINEAR_AXIS, JOYSTICK_NEUTRAL, JOYSTICK_STILL_RANGE

FULL_DEFLECTION = 127  # |value − 128| at which an axis reaches the profile's speed cap
BISECTION_STEPS = 20  # locating where a linear jog leaves the reachable space


def deflection(value: int) -> float:
    """−1…+1 for a joystick byte; 0 inside the still band."""
    low, high = JOYSTICK_STILL_RANGE
    if low <= value <= high:
        return 0.0
    return max(-1.0, min(1.0, (value - JOYSTICK_NEUTRAL) / FULL_DEFLECTION))


class JoystickMotion:
    """Joint or linear jogging from ``start_s`` on; ``joints_at(t)`` gives the pose."""

    def __init__(self, profile, speed_factor: float = 1.0) -> None:
        self.profile = profile
        self.speed_factor = speed_factor  # 1.3 = the arm jogs 30 % slower, like it moves
        self.joint_rates_deg_s = [0.0] * 6
        self.linear_rates_mm_s = [0.0] * 3
        self.start_s = 0.0
        self.start_joints: tuple[float, ...] = ()

    @property
    def active(self) -> bool:
        return any(self.joint_rates_deg_s) or any(self.linear_rates_mm_s)

    def set_axis(self, axis: int, values, joints_now: tuple[float, ...], now_s: float) -> None:
        """A joystick frame acts at ``now_s``; ``joints_now`` is where the arm is then."""
        self.start_s, self.start_joints = now_s, tuple(joints_now)
        if axis == JOYSTICK_LINEAR_AXIS:
            cap_mm_s = self.profile.speed.max_linear_mm_min / 60.0 / self.speed_factor
            self.linear_rates_mm_s = [deflection(v) * cap_mm_s for v in values]
        else:
            cap_deg_s = self.profile.speed.max_joint_deg_s / self.speed_factor
            self.joint_rates_deg_s[axis] = deflection(values[0]) * cap_deg_s

    def stop(self, joints_now: tuple[float, ...], now_s: float) -> None:
        self.joint_rates_deg_s = [0.0] * 6
        self.linear_rates_mm_s = [0.0] * 3
        self.start_s, self.start_joints = now_s, tuple(joints_now)

    def joints_at(self, now_s: float) -> tuple[float, ...]:
        if not self.active:
            return self.start_joints
        elapsed_s = max(0.0, now_s - self.start_s)
        joints = self._jog_joints(elapsed_s)
        if any(self.linear_rates_mm_s):
            joints = self._jog_linear(joints, elapsed_s)
        return joints

    def _jog_joints(self, elapsed_s: float) -> tuple[float, ...]:
        out = []
        for angle, rate, (low, high) in zip(self.start_joints, self.joint_rates_deg_s, self.profile.joint_limits_deg):
            out.append(min(high, max(low, angle + rate * elapsed_s)) if rate else angle)
        return tuple(out)

    def _jog_linear(self, joints: tuple[float, ...], elapsed_s: float) -> tuple[float, ...]:
        kinematics = self.profile.kinematics
        start = kinematics.forward(joints)

        def solve(t_s: float):
            pose = [start[k] + self.linear_rates_mm_s[k] * t_s for k in range(3)] + list(start[3:])
            try:
                return kinematics.inverse(pose, near=joints)
            except Unreachable:
                return None

        reached = solve(elapsed_s)
        if reached is not None:
            return reached
        good_s, bad_s, best = 0.0, elapsed_s, joints
        for _ in range(BISECTION_STEPS):
            middle_s = (good_s + bad_s) / 2
            found = solve(middle_s)
            if found is None:
                bad_s = middle_s
            else:
                good_s, best = middle_s, found
        return best
