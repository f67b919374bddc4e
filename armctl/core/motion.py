"""The motion-time model: how long each command takes and where the arm is meanwhile.

Strategy: ``MotionModel.plan(command, start)`` turns one protocol command into a ``Segment``
— a path (straight line, circular arc, straight line in joint space, or standing still)
and a 1-D speed profile along it made of at most three constant-acceleration pieces.
Planning does arithmetic only; ``Segment.sample(t)`` evaluates the profile and builds an
``ArmPose`` whose other half (joints of a Cartesian pose, or Cartesian of a joint pose) is
computed only when read, by IK near the last known joints or by FK.  The simulator, the
streamer, ``estimate`` and lint share this one model; every timing constant it needs comes
from the profile (all illustrative, see default_profile.toml).  No clock, no I/O.

This module is the planner (``MotionModel``, ``Planner``: commands → segments, the rules below)
and the façade of the model's parts, each importing only downwards: armctl/core/motion_pose.py
(``ArmPose``), armctl/core/motion_ramps.py (the time model: ``Ramp`` and its pieces) and
armctl/core/motion_paths.py (segment geometry, arcs, ``distance_to_path``).  Callers import every
name from here.

Rules (the protocol is silent on all of them; change them here and nowhere else):
- LinearMove: constant speed F (clamped to the profile's maximum).  Duration is the largest
  of distance / F, attitude change / ``attitude_deg_s`` (largest of |ΔB0|, |ΔB1|, |ΔW|, each
  the short way round) and external-axis change / ``max_joint_deg_s``; if nothing moves but
  the PWM changes, ``pwm_change_s``.  Pose, attitude and E0/E1 are interpolated linearly and
  synchronously; the PWM takes its new value as the segment begins.
- AccelLinearMove: real ramps along the line (speeds mm/min, H2; |K| clamped to the
  profile's maximum; K = 0 means constant speed1).  Mode 0: K > 0 accelerates from 0 to speed1
  then cruises (never reaching speed1 if short); K < 0 cruises at speed1 then decelerates to 0
  at the end (starting slower if short).  Mode 1: trapezoid 0 → speed1 → 0 (a triangle if
  short).  Mode 2: speed0 → speed1 at |K| (up or down), then cruise.  As for every Cartesian
  move, an attitude or E0/E1 change that needs longer than the path stretches its timing.
- JointMove: all joints (and E0/E1) synchronous; the lead joint moves at F deg/s with a start
  and a stop ramp of ``timing.joint_ramp_s[level-1]`` seconds each (constant acceleration
  F / ramp; a triangle if short), so a long move takes Δ/F + ramp.
- ArcStart takes no time; ArcEnd is the circle through the arc's start, ArcStart's point and
  its end point, at a speed changing linearly in time from ArcStart's F to ArcEnd's F (mm/min,
  H3).  ``plan`` needs the ArcStart (``arc_start=``); ``Planner`` keeps it for you.  Collinear
  or coincident points: a straight line, with ``Segment.note`` saying so.
- Delay: P ms.  MCode and control frames: 0 s and no motion (the simulator acts on them),
  except GoToPose: a joint move to the profile's fixed pose at ``max_joint_deg_s`` with
  smoothing ``timing.pose_smoothing``; SetWorktableOrigin changes the frame (below).
- ``timing.command_overhead_s`` is a wait at the start of every motion command and GoToPose
  (not ArcStart, not control frames).
- ``speed_factor`` multiplies the duration of every motion (moves, servo waits): 1.3 = an
  arm 30 % slower than commanded, 0.7 = 30 % faster.  Delays and the overhead are not scaled.
  It is the profile's ``[connector] speed_factor`` unless given (the simulator gives its own
  arm's): this is the one place it is applied, so estimate, lint, the streamer and plot agree.

Worktable frame (G54, SetWorktableOrigin X0 Y0 Z0, given in robot coordinates): a worktable
point p is the robot point p + (X0, Y0, Z0); attitude is not rotated.  Commands' X/Y/Z and the
reported X/Y/Z are worktable coordinates; ``ArmPose`` carries the origin it is expressed in.
"""

from __future__ import annotations

import math
from typing import Sequence

from .kinematics import Kinematics
from .motion_paths import (  # noqa: F401 - the façade offers the geometry's names
    Arc, ArcSegment, CartesianSegment, JointSegment, LineSegment, Segment, StillSegment, arc_through, circle_through,
    distance_to_path, on_path,
)
from .motion_pose import PWM_CHANNEL_COUNT, TINY_DEG, TINY_MM, ArmPose, short_deg  # noqa: F401
from .motion_ramps import NO_MOTION, Ramp, accel_pieces, joint_pieces, mm_s, piece_s, stretch
from .protocol import (
    AccelLinearMove, ArcEnd, ArcStart, Command, Delay, GoToPose, JointMove, LinearMove, SetWorktableOrigin,
    MOTION_COMMANDS,
)


# --- the model ------------------------------------------------------------------------------------


class MotionModel:
    """Plans protocol commands into segments with the profile's speeds and timing constants."""

    def __init__(self, profile, speed_factor: float | None = None):
        """``speed_factor``: the arm's real motion time ÷ the model's; None = the profile's
        ``[connector] speed_factor`` (the host's view of the arm; the simulator gives its own)."""
        if speed_factor is None:
            speed_factor = profile.connector.speed_factor
        if not speed_factor > 0:
            raise ValueError(f"speed_factor must be greater than 0, not {speed_factor!r}")
        self.profile, self.speed_factor = profile, speed_factor
        self.kinematics: Kinematics = profile.kinematics
        self._overhead_s = profile.timing.command_overhead_s
        self._handlers = {
            LinearMove: self._plan_linear, AccelLinearMove: self._plan_accel, JointMove: self._plan_joint_move,
            Delay: self._plan_delay, GoToPose: self._plan_go_to_pose, SetWorktableOrigin: self._plan_origin,
        }

    def initial_pose(self, joints: Sequence[float] | None = None, pwm_us: float | None = None,
                     origin_mm: Sequence[float] = (0.0, 0.0, 0.0)) -> ArmPose:
        """The arm at ``joints`` (default fixed pose 0), every PWM channel at ``pwm_us``
        (default ``pwm.initial_us``), E0 = E1 = 0."""
        pwm = self.profile.pwm.initial_us if pwm_us is None else pwm_us
        return ArmPose(self.kinematics, joints=self.profile.poses[0] if joints is None else joints,
                       pwm_us=(pwm,) * PWM_CHANNEL_COUNT, origin_mm=origin_mm)

    def reported_pose(self, xyz_mm: Sequence[float], joints: Sequence[float], pwm_us: float,
                      origin_mm: Sequence[float] = (0.0, 0.0, 0.0)) -> ArmPose:
        """The arm where it reports it is: X/Y/Z and joints as reported, neither derived from the
        other (an unverified profile's kinematics must not decide where a job starts); X/Y/Z
        turned from robot into worktable coordinates when the arm reports those (the profile's
        ``[connector] status_xyz_frame``).  Only the attitude, which no status frame reports, comes
        from the joints through the profile's forward kinematics."""
        if self.profile.connector.reports_robot_xyz:
            xyz_mm = [value - origin for value, origin in zip(xyz_mm, origin_mm)]
        attitude = self.kinematics.forward(joints)[3:]
        return ArmPose(self.kinematics, cartesian=(*xyz_mm, *attitude), joints=joints,
                       pwm_us=(pwm_us,) * PWM_CHANNEL_COUNT, origin_mm=origin_mm)

    def plan(self, command: Command, start: ArmPose, arc_start: ArcStart | None = None) -> Segment:
        """The segment ``command`` makes from ``start``.  An ArcEnd needs its ArcStart."""
        if type(command) is ArcEnd:
            return self._plan_arc(command, start, arc_start)
        handler = self._handlers.get(type(command))
        if handler is not None:
            return handler(command, start)
        if not isinstance(command, Command):
            raise TypeError(f"not a protocol command: {command!r}")
        segment = StillSegment(command, "still", start, start)  # ArcStart, MCode, control frames
        if type(command) in MOTION_COMMANDS and type(command) is not ArcStart:  # MCode
            segment._set_timing(NO_MOTION, wait_s=self._overhead_s)
        return segment

    # --- Cartesian ---

    def _speed(self, speed_mm_min: float, segment: Segment) -> float:
        """mm/s, clamped to the profile's maximum (noted on the segment)."""
        limit = self.profile.speed.max_linear_mm_min
        if speed_mm_min > limit:
            segment.note = speed_note(speed_mm_min, limit)
        return mm_s(speed_mm_min, limit)

    def _time_cartesian(self, segment: CartesianSegment, pieces) -> Segment:
        """How every Cartesian move is timed (``Planner.feed_s`` times a LinearMove with the
        same functions, without its segment): the path's ramp, stretched (``stretch``) when the
        attitude or the E axes need longer; without a path, the time they need, or the PWM
        change's (``_still_ramp``)."""
        other_s = self._other_s(segment.att_lead_deg, segment.ext_lead_deg)
        if segment.length:
            ramp = Ramp(pieces)
            return segment._set_timing(ramp, self.speed_factor * stretch(ramp.duration, other_s), self._overhead_s)
        return segment._set_timing(self._still_ramp(other_s, segment.start.pwm_us != segment.end.pwm_us),
                                   self.speed_factor, self._overhead_s)

    def _other_s(self, att_lead_deg: float, ext_lead_deg: float) -> float:
        """Seconds the attitude and the E axes need to turn through their leads (degrees)."""
        speed = self.profile.speed
        return max(att_lead_deg / speed.attitude_deg_s, ext_lead_deg / speed.max_joint_deg_s)

    def _still_ramp(self, other_s: float, pwm_changed: bool) -> Ramp:
        """The ramp of a Cartesian move without a path: as long as its attitude and E axes
        need (``other_s``), or as a PWM change if only that changes; one unit long."""
        if other_s <= 0 and pwm_changed:
            other_s = self.profile.timing.pwm_change_s
        return Ramp.constant(1.0, other_s)

    def _end_cartesian(self, command, start: ArmPose, pwm_us: tuple | None = None) -> ArmPose:
        return ArmPose.at_cartesian(
            self.kinematics, (command.x_mm, command.y_mm, command.z_mm, command.b0_deg, command.b1_deg, command.w_deg),
            start.pwm_us if pwm_us is None else pwm_us, command.e0_deg, command.e1_deg, start.origin_mm,
            start.known_joints,
        )

    def _plan_linear(self, command: LinearMove, start: ArmPose) -> Segment:
        pwm_us = start.pwm_us
        if pwm_us[command.pwm_channel - 1] != command.pwm_us:  # else the same values: no new tuple
            pwm_us = start.with_pwm(command.pwm_channel, command.pwm_us)
        end = self._end_cartesian(command, start, pwm_us)
        segment = LineSegment(command, start, end)
        v = self._speed(command.speed_mm_min, segment)
        return self._time_cartesian(segment, [(segment.length, v, v)])

    def _plan_accel(self, command: AccelLinearMove, start: ArmPose) -> Segment:
        segment = LineSegment(command, start, self._end_cartesian(command, start))
        v1 = self._speed(command.speed1_mm_min, segment)
        v0 = min(command.speed0_mm_min, self.profile.speed.max_linear_mm_min) / 60.0
        accel = max(-self.profile.speed.max_accel_mm_s2, min(command.accel_mm_s2, self.profile.speed.max_accel_mm_s2))
        if accel == 0:
            segment.note = "acceleration 0: planned at constant speed1"
            pieces = [(segment.length, v1, v1)]
        else:
            pieces = accel_pieces(command.mode, segment.length, accel, v1, v0)
        return self._time_cartesian(segment, pieces)

    def _plan_arc(self, command: ArcEnd, start: ArmPose, arc_start: ArcStart | None) -> Segment:
        end = self._end_cartesian(command, start, start.with_pwm(1, command.pwm_us))
        if arc_start is None:
            segment = LineSegment(command, start, end)
            v = self._speed(command.speed_mm_min or self.profile.speed.max_linear_mm_min, segment)
            segment.note = "arc end without its arc start: planned as a straight line"
            return self._time_cartesian(segment, [(segment.length, v, v)])
        arc = arc_through(start.xyz, (arc_start.x_mm, arc_start.y_mm, arc_start.z_mm), end.xyz)
        segment = LineSegment(command, start, end) if arc is None else ArcSegment(command, start, end, arc)
        v_start = self._speed(arc_start.speed_mm_min, segment)
        v_end = self._speed(command.speed_mm_min, segment)
        if arc is None:
            segment.note = "arc points are collinear or coincide: planned as a straight line"
        elif abs(arc.radius_mm - arc_start.radius_mm) > max(0.5, 0.01 * arc.radius_mm):
            segment.note = (f"arc radius R{arc_start.radius_mm:g} differs from the circle through the points"
                            f" (radius {arc.radius_mm:.3f} mm)")
        return self._time_cartesian(segment, [(segment.length, v_start, v_end)])

    # --- joints ---

    def _joint(self, command, start: ArmPose, joints, speed_deg_s: float, smoothing: int, pwm_us, e0, e1) -> Segment:
        end = ArmPose(self.kinematics, joints=joints, pwm_us=pwm_us, e0_deg=e0, e1_deg=e1, origin_mm=start.origin_mm)
        segment = JointSegment(command, start, end)
        limit = self.profile.speed.max_joint_deg_s
        if speed_deg_s > limit:
            segment.note = f"joint speed {speed_deg_s:g} deg/s clamped to the profile's {limit:g} deg/s"
            speed_deg_s = limit
        if segment.length:
            ramp = Ramp(joint_pieces(segment.length, speed_deg_s, self.profile.timing.ramp_s(smoothing)))
        elif start.pwm_us != end.pwm_us:
            ramp = Ramp.constant(1.0, self.profile.timing.pwm_change_s)
        else:
            ramp = NO_MOTION
        return segment._set_timing(ramp, self.speed_factor, self._overhead_s)

    def _joint_speed(self, command) -> tuple[float, int]:
        """A joint move's speed (deg/s, before the profile's limit) and smoothing level: a fixed
        pose goes at the profile's."""
        if isinstance(command, GoToPose):
            return self.profile.speed.max_joint_deg_s, self.profile.timing.pose_smoothing
        return command.speed_deg_s, command.smoothing

    def _plan_joint_move(self, command: JointMove, start: ArmPose) -> Segment:
        return self._joint(command, start, command.joints_deg, *self._joint_speed(command),
                           start.with_pwm(1, command.pwm_us), command.e0_deg, command.e1_deg)

    def _plan_go_to_pose(self, command: GoToPose, start: ArmPose) -> Segment:
        return self._joint(command, start, self.profile.poses[command.pose], *self._joint_speed(command),
                           start.pwm_us, start.e0_deg, start.e1_deg)

    def joint_move_from_anywhere_s(self, segment: Segment) -> float:
        """How much longer than ``segment`` (a joint move or a fixed pose, planned) its motion may
        take from any start within the profile's joint limits, in the model's seconds: where the
        move before it (a Cartesian one) left the joints only the arm's own IK knows when the
        profile's kinematics are not verified — a 5 % error in the links moves an IK solution by
        up to 36 degrees on the default profile.  And at least a whole turn: the limits are the
        profile's too, and an arm whose links differ may find its only solution past them (the
        simulator's IK then ignores them: 124 degrees past J5's found)."""
        speed_deg_s, smoothing = self._joint_speed(segment.command)
        speed_deg_s = min(speed_deg_s, self.profile.speed.max_joint_deg_s)
        lead_deg = max(360.0, max(max(angle - low, high - angle)
                                  for angle, (low, high) in zip(segment.end.joints, self.profile.joint_limits_deg)))
        ramp = Ramp(joint_pieces(lead_deg, speed_deg_s, self.profile.timing.ramp_s(smoothing)))
        return ramp.duration * self.speed_factor

    # --- the rest ---

    def _plan_delay(self, command: Delay, start: ArmPose) -> Segment:
        segment = StillSegment(command, "still", start, start)
        return segment._set_timing(Ramp.constant(1.0, command.delay_ms / 1000.0), 1.0, self._overhead_s)

    def _plan_origin(self, command: SetWorktableOrigin, start: ArmPose) -> Segment:
        end = start.replace(origin_mm=(command.x_mm, command.y_mm, command.z_mm))
        return StillSegment(command, "still", start, end)


def speed_note(speed_mm_min: float, limit_mm_min: float) -> str:
    """The note of a Cartesian move whose speed the profile's maximum clamps."""
    return f"speed {speed_mm_min:g} mm/min clamped to the profile's {limit_mm_min:g} mm/min"


class Planner:
    """Plans a command stream in order: keeps the current pose and a pending ArcStart.

    ``feed(command)`` returns the command's segment and moves ``pose`` to its end.  An ArcStart
    is remembered for the ArcEnd that must follow it; any other command forgets it.
    ``feed_s(command)`` is ``feed(command).duration_s`` for a caller that needs the time alone
    (lint's E012 clock, issue 13): a LinearMove is then timed without building its segment or
    its end pose — ``pose`` builds that pose when it is next read, as ``feed`` would have.
    ``feed_line(command)`` is the same for a LinearMove, with its segment's length too (the
    estimate: its path length; issue 23).
    """

    def __init__(self, model: MotionModel, start: ArmPose | None = None):
        self.model = model
        self.pose = model.initial_pose() if start is None else start
        self.pending_arc: ArcStart | None = None
        self._line_constants = None  # feed_s's profile numbers, read on its first LinearMove

    @property
    def pose(self) -> ArmPose:
        if self._line_end is not None:  # the end of the LinearMoves feed_s timed, built now
            x, y, z, b0, b1, w, pwm_us, e0, e1 = self._line_end
            origin_mm, hint = self._line_base
            self._pose = ArmPose(self.model.kinematics, cartesian=(x, y, z, b0, b1, w), pwm_us=pwm_us, e0_deg=e0,
                                 e1_deg=e1, origin_mm=origin_mm, hint=hint)
            self._line_end = None
        return self._pose

    @pose.setter
    def pose(self, value: ArmPose) -> None:
        self._pose, self._line_end = value, None

    def feed(self, command: Command) -> Segment:
        segment = self.model.plan(command, self.pose, self.pending_arc)
        self.pending_arc = command if isinstance(command, ArcStart) else None
        self.pose = segment.end
        return segment

    def feed_s(self, command: Command) -> float:
        """``feed(command).duration_s``; a LinearMove costs a few float operations.

        The move is timed with ``_time_cartesian``'s functions (``_other_s``, ``stretch``,
        ``_still_ramp``) from its length, speed (``mm_s``) and one constant-speed piece
        (``piece_s``, as ``Ramp`` times it): one rule, so the seconds are the same float
        (tests/test_lint_fastpaths.py holds the two equal).  A chain of LinearMoves keeps the
        origin and IK hint of the pose it starts from: a LinearMove's end carries its start's
        (``_end_cartesian``), and no one can read the joints of an end pose that is not built,
        so the hint stays the chain's first."""
        if type(command) is not LinearMove or not command.speed_mm_min > 0:
            return self.feed(command).duration_s
        return self.feed_line(command)[0]

    def feed_line(self, command: LinearMove) -> tuple[float, float]:
        """``(segment.duration_s, segment.length)`` of ``feed(command)`` for a LinearMove whose
        speed is above 0 (``feed_s``'s arithmetic; the segment's length is 0.0 for a move
        shorter than ``TINY_MM``, as ``LineSegment`` has it)."""
        end = self._line_end
        if end is None:
            start = self._pose
            sx, sy, sz, sb0, sb1, sw = start.cartesian
            spwm, se0, se1 = start.pwm_us, start.e0_deg, start.e1_deg
            self._line_base = (start.origin_mm, start.known_joints)  # as _end_cartesian reads them now
        else:
            sx, sy, sz, sb0, sb1, sw, spwm, se0, se1 = end
        constants = self._line_constants
        if constants is None:
            model = self.model
            constants = self._line_constants = (model.profile.speed.max_linear_mm_min, model._overhead_s,
                                                model.speed_factor)
        max_mm_min, overhead_s, speed_factor = constants
        x, y, z, b0, b1, w = command.x_mm, command.y_mm, command.z_mm, command.b0_deg, command.b1_deg, command.w_deg
        e0, e1 = command.e0_deg, command.e1_deg
        channel, pwm_us = command.pwm_channel - 1, command.pwm_us
        if spwm[channel] == pwm_us:
            pwm = spwm  # the common case: the same values, no new tuple
        else:
            pwm = list(spwm)
            pwm[channel] = pwm_us
            pwm = tuple(pwm)
        self._line_end = (x, y, z, b0, b1, w, pwm, e0, e1)
        self.pending_arc = None
        if b0 == sb0 and b1 == sb1 and w == sw and e0 == se0 and e1 == se1:
            other_s = 0.0  # no lead turns in no time: a run of lines rarely turns the tool
        else:  # the leads as CartesianSegment measures them
            other_s = self.model._other_s(max(abs(short_deg(b0 - sb0)), abs(short_deg(b1 - sb1)), abs(short_deg(w - sw))),
                                          max(abs(e0 - se0), abs(e1 - se1)))
        dx, dy, dz = x - sx, y - sy, z - sz
        length = math.sqrt(dx * dx + dy * dy + dz * dz)  # LineSegment's norm3
        if length > TINY_MM:  # _time_cartesian's path: one constant-speed piece, its Ramp's duration
            path_s = piece_s(length, v := mm_s(command.speed_mm_min, max_mm_min), v)
            return overhead_s + path_s * (speed_factor * stretch(path_s, other_s)), length  # as Segment._set_timing
        return overhead_s + self.model._still_ramp(other_s, spwm != pwm).duration * speed_factor, 0.0

    def feed_all(self, commands) -> list[Segment]:
        return [self.feed(command) for command in commands]
