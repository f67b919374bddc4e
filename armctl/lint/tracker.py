"""Where lint believes the arm is between statements: pose, joints, origin, PWM, pause.

Strategy: the compiler knows what was *written* (modal values); rules need what the arm will
*do*: the robot-frame position a worktable target means after G54, the Cartesian point a G6
or POSE leaves the tool at (forward kinematics), the start point of an arc, the last PWM sent
to each channel and the pause toggles.  ``ArmTracker.apply(statement)`` advances this picture
after the rules have looked at the statement; anything lint cannot know (after PROGRAM n or
RESET, before the first move) is ``None`` and the rules that need it stay silent.

Assumption (stated in docs/lint.md): a script that never sends G54 runs with the worktable
origin at the robot origin (0, 0, 0).  Pure: no I/O, only the profile's kinematics.
"""

from __future__ import annotations

from typing import Optional

from ..core.kinematics import SolvableCells
from ..core.protocol import (
    AccelLinearMove, ArcEnd, ArcStart, GoToPose, JointMove, LinearMove, PauseToggle, ResetArm, RunProgram,
    SetWorktableOrigin,
)

Pose = tuple[float, float, float, float, float, float]
_CARTESIAN_TARGETS = (LinearMove, AccelLinearMove, ArcEnd)
_REACH_CACHE_SIZE = 4096
_COARSE_CELL_MM = 32.0  # twice kinematics.SolvableCells' default 16 mm
_MISSING = object()


def cartesian_target(command) -> Pose:
    return (command.x_mm, command.y_mm, command.z_mm, command.b0_deg, command.b1_deg, command.w_deg)


def pwm_channel_of(command) -> Optional[int]:
    """The PWM channel a frame's S value drives, or None for frames without PWM."""
    if type(command) is LinearMove:
        return command.pwm_channel
    if type(command) in (JointMove, ArcStart, ArcEnd):
        return 1  # these frames have no channel byte: PROTOCOL.md, their S drives channel 1
    return None


class ArmTracker:
    """The arm as lint follows it through one script (see the module docstring)."""

    def __init__(self, profile) -> None:
        self.profile = profile
        self.origin_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.pose: Optional[Pose] = None  # worktable frame
        self.joints: Optional[tuple[float, ...]] = None  # known only after G6 / POSE
        self.arc_start = None  # the pending G300 Statement
        self.arc_from: Optional[Pose] = None  # where the arm was when the G300 came
        self.pwm_us: dict[int, float] = {}  # channel → last value sent
        self.pwm_statement: dict[int, object] = {}  # channel → last Statement that wrote S
        self.pause_count = 0
        self.last_pause = None  # the last PAUSE Statement
        self.statements = 0
        self.last_statement = None
        self.notes: set = set()  # what a rule already said once per script, e.g. ("L301", channel)
        self._reach: dict = {}  # (pose, origin, joints) → reach problem or None
        # robot-frame poses inside the workspace with a joint solution, a proven cube at a time:
        # first a 32 mm cube (one proof stands for eight of 16 mm, issue 13: a walk through
        # fresh space spent ~1.6 µs a line on proofs), then, near a limit where the large one
        # fails, the 16 mm cube; each is sound on its own (tests/test_lint_fastpaths.py)
        self._coarse_cells = SolvableCells(profile.links, profile.joint_limits_deg, profile.workspace, _COARSE_CELL_MM)
        self._cells = SolvableCells(profile.links, profile.joint_limits_deg, profile.workspace)

    # --- what rules ask -----------------------------------------------------------------------

    def robot_xyz(self, pose) -> tuple[float, float, float]:
        """A worktable point in the robot frame."""
        ox, oy, oz = self.origin_mm
        return (pose[0] + ox, pose[1] + oy, pose[2] + oz)

    def ik_hint(self):
        """Joints to solve IK near: the last known joints, else None (the profile's home pose)."""
        return self.joints

    def surely_reachable(self, pose) -> bool:
        """True when the worktable ``pose`` lies in a cube proven inside the workspace box and
        solvable near the IK hint (kinematics.SolvableCells); False: not known, ask
        ``reach_problem``.  The common case of every target, at the cost of a look-up."""
        ox, oy, oz = self.origin_mm
        near = self.joints
        robot = (pose[0] + ox, pose[1] + oy, pose[2] + oz, pose[3], pose[4], pose[5])
        near = self.profile.poses[0] if near is None else near
        return self._coarse_cells.proven(robot, near) or self._cells.proven(robot, near)

    def reach_problem(self, pose, compute):
        """``compute()`` (rules.py: None, or the problem with its hint) for ``pose`` here, cached:
        loops and palettes revisit the same targets."""
        key = (pose, self.origin_mm, self.joints)
        found = self._reach.get(key, _MISSING)
        if found is _MISSING:
            if len(self._reach) >= _REACH_CACHE_SIZE:
                self._reach.clear()
            found = self._reach[key] = compute()
        return found

    # --- advancing ------------------------------------------------------------------------------

    def apply(self, statement) -> None:
        command = statement.command
        if type(command) is not LinearMove:
            self.apply_any(statement)
            return
        # most statements (issue 13): what apply_any does for a LinearMove, without its tests
        # (tests/test_lint_tracker_fastpath.py holds the two equal)
        self.statements += 1
        self.last_statement = statement
        channel = command.pwm_channel  # pwm_channel_of(command)
        self.pwm_us[channel] = command.pwm_us
        if "S" in statement.words:
            self.pwm_statement[channel] = statement
        self.arc_start = self.arc_from = self.joints = None
        self.pose = (command.x_mm, command.y_mm, command.z_mm, command.b0_deg, command.b1_deg, command.w_deg)

    def apply_any(self, statement) -> None:
        """``apply`` for a statement of any kind."""
        command = statement.command
        kind = type(command)
        self.statements += 1
        self.last_statement = statement
        channel = pwm_channel_of(command)
        if channel is not None:
            self.pwm_us[channel] = command.pwm_us
            if "S" in statement.words:
                self.pwm_statement[channel] = statement
        if kind is ArcStart:
            self.arc_start, self.arc_from = statement, self.pose
            return
        self.arc_start = self.arc_from = None
        if kind in _CARTESIAN_TARGETS:
            self.pose = cartesian_target(command)
        elif kind is JointMove:
            self._at_joints(command.joints_deg)
        elif kind is GoToPose:
            self._at_joints(self.profile.poses[command.pose])
        elif kind is SetWorktableOrigin:
            self._set_origin((command.x_mm, command.y_mm, command.z_mm))
        elif kind in (RunProgram, ResetArm):
            self.pose = self.joints = None  # the arm goes where the program (or reset) takes it
        elif kind is PauseToggle:
            self.pause_count += 1
            self.last_pause = statement
        if kind in _CARTESIAN_TARGETS:
            self.joints = None

    def _at_joints(self, joints) -> None:
        self.joints = tuple(joints)
        x, y, z, b0, b1, w = self.profile.kinematics.forward(self.joints)
        ox, oy, oz = self.origin_mm
        self.pose = (x - ox, y - oy, z - oz, b0, b1, w)

    def _set_origin(self, origin) -> None:
        if self.pose is not None:  # the arm stays put; its worktable coordinates shift
            x, y, z = self.robot_xyz(self.pose)
            self.pose = (x - origin[0], y - origin[1], z - origin[2], *self.pose[3:])
        self.origin_mm = origin

    @property
    def paused(self) -> bool:
        return self.pause_count % 2 == 1
