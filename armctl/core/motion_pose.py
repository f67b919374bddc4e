"""Where the arm is: ``ArmPose``, either half of it (Cartesian pose or joints) computed from the other on first read.

Strategy: a pose is built from what is known — a Cartesian pose (a command's target, a path's
point) or joints (a joint move's target, a report) — and the other half is derived only when
someone reads it: IK nearest ``hint`` (the last known joints) or FK, through the profile's
``Kinematics``.  ``xyz_derived`` / ``joints_derived`` say which half came from the profile's
kinematics, not from a command or a report.  Worktable frame (G54): a worktable point p is the
robot point p + ``origin_mm``; attitude is not rotated.  Part of the motion model
(armctl/core/motion.py is its façade); no clock, no I/O.
"""

from __future__ import annotations

from typing import Sequence

from .kinematics import CartesianPose, Kinematics

PWM_CHANNEL_COUNT = 4
TINY_MM = 1e-6  # shorter Cartesian distances count as no motion
TINY_DEG = 1e-6
_new_pose = object.__new__  # ArmPose.at_cartesian
_new_tuple = tuple.__new__  # a CartesianPose (a NamedTuple) from its six values, as its __new__ builds it


def short_deg(delta: float) -> float:
    """An angle difference taken the short way round, in [−180, 180)."""
    return (delta + 180.0) % 360.0 - 180.0


# --- the arm's state ----------------------------------------------------------------------------


class ArmPose:
    """Where the arm is: Cartesian pose (worktable frame), joints, PWM per channel, E0, E1.

    Built from either half; the other half is computed on first read (IK nearest ``hint``, the
    last known joints; FK).  A Cartesian pose the arm cannot reach keeps ``hint`` as joints.
    ``pwm_us[k]`` is channel k + 1.  Treat it as immutable; ``replace`` makes a changed copy.
    """

    __slots__ = ("kinematics", "_cartesian", "_joints", "_hint", "pwm_us", "e0_deg", "e1_deg", "origin_mm",
                 "xyz_derived", "joints_derived")

    def __init__(self, kinematics: Kinematics, *, cartesian: Sequence[float] | None = None,
                 joints: Sequence[float] | None = None, pwm_us: Sequence[float] = (1500.0,) * PWM_CHANNEL_COUNT,
                 e0_deg: float = 0.0, e1_deg: float = 0.0, origin_mm: Sequence[float] = (0.0, 0.0, 0.0),
                 hint: Sequence[float] | None = None):
        if cartesian is None and joints is None:
            raise ValueError("an ArmPose needs its Cartesian pose or its joints")
        self.kinematics = kinematics
        self._cartesian = None if cartesian is None else CartesianPose(*cartesian)
        self._joints = None if joints is None else tuple(joints)
        # X/Y/Z come from the profile's forward kinematics (built from joints alone), not from a
        # command or a report: an unverified profile's FK must not decide what the arm did.
        self.xyz_derived = cartesian is None
        self.joints_derived = joints is None  # likewise: joints from the profile's IK
        self._hint = tuple(hint) if hint is not None else kinematics.home
        self.pwm_us = tuple(pwm_us)
        self.e0_deg, self.e1_deg = e0_deg, e1_deg
        self.origin_mm = tuple(origin_mm)

    @classmethod
    def at_cartesian(cls, kinematics: Kinematics, cartesian: tuple, pwm_us: tuple, e0_deg: float, e1_deg: float,
                     origin_mm: tuple, hint: tuple) -> "ArmPose":
        """``ArmPose(kinematics, cartesian=…, pwm_us=…, e0_deg=…, e1_deg=…, origin_mm=…, hint=…)`` for
        a caller whose ``cartesian`` is six numbers and whose ``pwm_us``, ``origin_mm`` and ``hint``
        are tuples already (the planner's every Cartesian end, three per move of a run): the same
        pose, built without the keyword parsing and the copies (``tuple`` of a tuple is itself)."""
        pose = _new_pose(cls)
        pose.kinematics, pose._joints, pose._hint = kinematics, None, hint
        pose._cartesian = _new_tuple(CartesianPose, cartesian)
        pose.xyz_derived, pose.joints_derived = False, True
        pose.pwm_us, pose.e0_deg, pose.e1_deg, pose.origin_mm = pwm_us, e0_deg, e1_deg, origin_mm
        return pose

    @property
    def cartesian(self) -> CartesianPose:
        """Tool pose in the worktable frame (x, y, z mm; b0, b1, w deg)."""
        if self._cartesian is None:
            x, y, z, b0, b1, w = self.kinematics.forward(self._joints)
            ox, oy, oz = self.origin_mm
            self._cartesian = CartesianPose(x - ox, y - oy, z - oz, b0, b1, w)
        return self._cartesian

    @property
    def xyz(self) -> tuple[float, float, float]:
        return self.cartesian[:3]

    @property
    def robot_cartesian(self) -> CartesianPose:
        """Tool pose in the robot frame."""
        x, y, z, b0, b1, w = self.cartesian
        ox, oy, oz = self.origin_mm
        return CartesianPose(x + ox, y + oy, z + oz, b0, b1, w)

    @property
    def joints(self) -> tuple[float, ...]:
        """J1…J6 in degrees."""
        if self._joints is None:
            self._joints = self.kinematics.joints_of(self.robot_cartesian, self._hint)
        return self._joints

    @property
    def ik_hint(self) -> tuple[float, ...]:
        """The joints the IK of this pose starts near (those of a pose sampled on a path)."""
        return self._hint

    @property
    def known_joints(self) -> tuple[float, ...]:
        """The joints if known, else the hint they will be computed near (no IK)."""
        return self._joints if self._joints is not None else self._hint

    def replace(self, *, cartesian=None, joints=None, pwm_us=None, e0_deg=None, e1_deg=None,
                origin_mm=None) -> "ArmPose":
        """A copy with some parts changed.  A new origin alone keeps the arm where it is."""
        if cartesian is None and joints is None:
            joints = None if self.joints_derived else self._joints
            cartesian = None if self.xyz_derived else self._cartesian
            if origin_mm is not None and cartesian is not None:
                shift = [self.origin_mm[k] - origin_mm[k] for k in range(3)]
                cartesian = (cartesian[0] + shift[0], cartesian[1] + shift[1], cartesian[2] + shift[2], *cartesian[3:])
        return ArmPose(
            self.kinematics, cartesian=cartesian, joints=joints,
            pwm_us=self.pwm_us if pwm_us is None else pwm_us,
            e0_deg=self.e0_deg if e0_deg is None else e0_deg, e1_deg=self.e1_deg if e1_deg is None else e1_deg,
            origin_mm=self.origin_mm if origin_mm is None else origin_mm, hint=self.known_joints,
        )

    def with_pwm(self, channel: int, value_us: float) -> tuple[float, ...]:
        """``pwm_us`` with channel 1…4 set to ``value_us``."""
        pwm = list(self.pwm_us)
        pwm[channel - 1] = value_us
        return tuple(pwm)

    def _key(self):
        return self.cartesian, self.joints, self.pwm_us, self.e0_deg, self.e1_deg, self.origin_mm

    def __eq__(self, other) -> bool:
        return self is other or (isinstance(other, ArmPose) and self._key() == other._key())

    __hash__ = None

    def isclose(self, other: "ArmPose", mm: float = 1e-6, deg: float = 1e-6) -> bool:
        """Same pose within tolerances (attitude compared the short way round)."""
        a, b = self.cartesian, other.cartesian
        return (
            all(abs(a[k] - b[k]) <= mm for k in range(3))
            and all(abs(short_deg(a[k] - b[k])) <= deg for k in range(3, 6))
            and all(abs(p - q) <= deg for p, q in zip(self.joints, other.joints))
            and self.pwm_us == other.pwm_us and abs(self.e0_deg - other.e0_deg) <= deg
            and abs(self.e1_deg - other.e1_deg) <= deg and self.origin_mm == other.origin_mm
        )

    def __repr__(self) -> str:
        c = ", ".join(f"{v:.3f}" for v in self.cartesian)
        j = ", ".join(f"{v:.3f}" for v in self.joints)
        return f"ArmPose(cartesian=({c}), joints=({j}), pwm_us={self.pwm_us}, e=({self.e0_deg:g}, {self.e1_deg:g}))"
