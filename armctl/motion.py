"""The motion-time model: how long each command takes and where the arm is meanwhile.

Strategy: ``MotionModel.plan(command, start)`` turns one protocol command into a ``Segment``
— a path (straight line, circular arc, straight line in joint space, or standing still)
and a 1-D speed profile along it made of at most three constant-acceleration pieces.
Planning does arithmetic only; ``Segment.sample(t)`` evaluates the profile and builds an
``ArmPose`` whose other half (joints of a Cartesian pose, or Cartesian of a joint pose) is
computed only when read, by IK near the last known joints or by FK.  The simulator, the
streamer, ``estimate`` and lint share this one model; every timing constant it needs comes
from the profile (all illustrative, see default_profile.toml).  No clock, no I/O.

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
from typing import NamedTuple, Sequence

from .kinematics import CartesianPose, Kinematics
from .protocol import (
    AccelLinearMove, ArcEnd, ArcStart, Command, Delay, GoToPose, JointMove, LinearMove, SetWorktableOrigin,
    MOTION_COMMANDS,
)

PWM_CHANNEL_COUNT = 4
TINY_MM = 1e-6  # shorter Cartesian distances count as no motion
TINY_DEG = 1e-6
_FK_POLYLINE_POINTS = 16  # joint segments matched against a Cartesian observation


def _short(delta: float) -> float:
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
            and all(abs(_short(a[k] - b[k])) <= deg for k in range(3, 6))
            and all(abs(p - q) <= deg for p, q in zip(self.joints, other.joints))
            and self.pwm_us == other.pwm_us and abs(self.e0_deg - other.e0_deg) <= deg
            and abs(self.e1_deg - other.e1_deg) <= deg and self.origin_mm == other.origin_mm
        )

    def __repr__(self) -> str:
        c = ", ".join(f"{v:.3f}" for v in self.cartesian)
        j = ", ".join(f"{v:.3f}" for v in self.joints)
        return f"ArmPose(cartesian=({c}), joints=({j}), pwm_us={self.pwm_us}, e=({self.e0_deg:g}, {self.e1_deg:g}))"


# --- speed profiles -------------------------------------------------------------------------------


def _piece_s(distance: float, v_from: float, v_to: float) -> float:
    """Seconds to cover ``distance`` at constant acceleration from ``v_from`` to ``v_to``."""
    return 2.0 * distance / (v_from + v_to)


def _stretch(path_s: float, other_s: float) -> float:
    """The factor a path's seconds are stretched by so that the attitude and the E axes, which
    need ``other_s``, finish with it."""
    return other_s / path_s if other_s > path_s > 0 else 1.0


def _mm_s(speed_mm_min: float, limit_mm_min: float) -> float:
    """A Cartesian speed in mm/s, clamped to the profile's maximum."""
    return min(speed_mm_min, limit_mm_min) / 60.0


class _Ramp:
    """Distance along a path as a function of time: pieces of constant acceleration."""

    __slots__ = ("length", "duration", "_pieces")

    def __init__(self, pieces: Sequence[tuple[float, float, float]]):
        """``pieces``: (distance, speed at its start, speed at its end); speeds must not both be 0."""
        t = s = 0.0
        out = []
        for distance, v_from, v_to in pieces:
            if distance > 0:
                dt = _piece_s(distance, v_from, v_to)
                out.append((t, s, v_from, (v_to - v_from) / dt))
                t += dt
                s += distance
        self.length, self.duration, self._pieces = s, t, tuple(reversed(out))

    @classmethod
    def constant(cls, length: float, duration: float) -> "_Ramp":
        return cls([(length, length / duration, length / duration)] if duration > 0 else [])

    def distance_at(self, t: float) -> float:
        if t >= self.duration:
            return self.length
        for t0, s0, v0, a in self._pieces:
            if t >= t0:
                dt = t - t0
                s = s0 + v0 * dt + 0.5 * a * dt * dt
                return self.length if self.length < s else s  # min(s, length), without the call
        return 0.0

    def time_at(self, s: float) -> float:
        if s >= self.length:
            return self.duration
        for t0, s0, v0, a in self._pieces:
            if s >= s0:
                ds = s - s0
                return t0 + 2.0 * ds / (v0 + math.sqrt(max(v0 * v0 + 2.0 * a * ds, 0.0))) if ds > 0 else t0
        return 0.0


def _accel_pieces(mode: int, length: float, accel: float, v1: float, v0: float):
    """Pieces of an AccelLinearMove (mm, mm/s, mm/s²), see the module docstring."""
    a = abs(accel)
    ramp = v1 * v1 / (2.0 * a)
    if mode == 0 and accel > 0:
        return [(length, 0.0, math.sqrt(2 * a * length))] if ramp >= length else [(ramp, 0.0, v1), (length - ramp, v1, v1)]
    if mode == 0:
        return [(length, math.sqrt(2 * a * length), 0.0)] if ramp >= length else [(length - ramp, v1, v1), (ramp, v1, 0.0)]
    if mode == 1:
        if 2 * ramp >= length:
            peak = math.sqrt(a * length)
            return [(length / 2, 0.0, peak), (length / 2, peak, 0.0)]
        return [(ramp, 0.0, v1), (length - 2 * ramp, v1, v1), (ramp, v1, 0.0)]
    ramp = abs(v1 * v1 - v0 * v0) / (2.0 * a)
    if ramp >= length:
        sign = 1.0 if v1 >= v0 else -1.0
        return [(length, v0, math.sqrt(max(v0 * v0 + sign * 2 * a * length, 0.0)))]
    return [(ramp, v0, v1), (length - ramp, v1, v1)]


def _joint_pieces(lead_deg: float, speed: float, ramp_s: float):
    if ramp_s <= 0:
        return [(lead_deg, speed, speed)]
    ramp = speed * ramp_s / 2.0  # distance covered while ramping at speed / ramp_s
    if 2 * ramp >= lead_deg:
        peak = math.sqrt(speed / ramp_s * lead_deg)
        return [(lead_deg / 2, 0.0, peak), (lead_deg / 2, peak, 0.0)]
    return [(ramp, 0.0, speed), (lead_deg - 2 * ramp, speed, speed), (ramp, speed, 0.0)]


# --- arc geometry (also for lint) -----------------------------------------------------------------


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _norm(a):
    return math.sqrt(_dot(a, a))


class Arc(NamedTuple):
    center: tuple[float, float, float]
    radius_mm: float
    normal: tuple[float, float, float]  # unit; start → via → end turns counter-clockwise about it
    sweep_rad: float  # angle from start to end through via, in (0, 2π)

    @property
    def length_mm(self) -> float:
        return self.radius_mm * self.sweep_rad


def circle_through(p0, p1, p2, tol_mm: float = 1e-6):
    """(center, radius, unit normal) of the circle through three points, or None when two
    points coincide or all three lie on one line (within ``tol_mm``)."""
    a, b = _sub(p0, p2), _sub(p1, p2)
    axb = _cross(a, b)
    area2 = _norm(axb)  # twice the triangle's area
    longest = max(_norm(a), _norm(b), _norm(_sub(p1, p0)))
    if longest <= tol_mm or area2 / longest <= tol_mm:  # area2 / longest = smallest altitude
        return None
    k = 1.0 / (2.0 * area2 * area2)
    m = tuple(_dot(a, a) * b[i] - _dot(b, b) * a[i] for i in range(3))
    offset = _cross(m, axb)
    center = tuple(p2[i] + offset[i] * k for i in range(3))
    normal = _cross(_sub(p1, p0), _sub(p2, p1))
    n = _norm(normal)
    return center, _norm(_sub(p0, center)), (normal[0] / n, normal[1] / n, normal[2] / n)


def arc_through(p0, p1, p2, tol_mm: float = 1e-6) -> Arc | None:
    """The arc from ``p0`` through ``p1`` to ``p2``, or None (see circle_through)."""
    circle = circle_through(p0, p1, p2, tol_mm)
    if circle is None:
        return None
    center, radius, normal = circle
    u = _sub(p0, center)
    v = _cross(normal, u)
    w = _sub(p2, center)
    sweep = math.atan2(_dot(w, v), _dot(w, u)) % (2 * math.pi)
    return Arc(center, radius, normal, sweep or 2 * math.pi)


# --- segments -------------------------------------------------------------------------------------

_NO_MOTION = _Ramp([])
_SPACES = {"line": "cartesian", "arc": "cartesian", "joint": "joint"}


class Segment:
    """One command's motion.

    ``kind``: "line", "arc", "joint" or "still".  ``length``: the path's length — mm for
    line and arc, lead-joint degrees for joint, 0 for still and for a line without Cartesian
    motion (attitude-, E- or PWM-only).  ``note``: None, or how the plan departs from the
    command (a clamped speed, an arc planned as a line).  ``duration_s`` includes the
    speed factor and the overhead.  ``sample(t)`` is the pose t seconds after the segment
    began, clamped: ``sample(t ≤ 0)`` is ``start`` (for a segment that takes time) and
    ``sample(t ≥ duration_s)`` is ``end``.
    """

    __slots__ = ("command", "kind", "start", "end", "length", "note", "duration_s", "_ramp", "_scale", "_wait")

    def __init__(self, command, kind: str, start: ArmPose, end: ArmPose, length: float = 0.0):
        self.command, self.kind, self.start, self.end, self.length = command, kind, start, end, length
        self.note: str | None = None
        self._set_timing(_NO_MOTION)

    def _set_timing(self, ramp: _Ramp, scale: float = 1.0, wait_s: float = 0.0) -> "Segment":
        self._ramp, self._scale, self._wait = ramp, scale, wait_s
        self.duration_s = wait_s + ramp.duration * scale
        return self

    @property
    def space(self) -> str | None:
        """Where its path lives: "cartesian" (line, arc), "joint" or None (still)."""
        return _SPACES.get(self.kind)

    @property
    def moves_reported(self) -> bool:
        """Whether the arm's status reports show this motion: its position or joints change (an
        attitude-only move turns the wrist joints).  E0/E1 are in no status kind, and a PWM change
        is no move: a segment that changes only those takes its time (here, in the simulator, on
        the arm) with every reading still — the job engine's end of motion must not end there."""
        if self.kind == "still":
            return False
        if self.length > 0:
            return True
        return max(abs(a - b) for a, b in zip(self.start.joints, self.end.joints)) > TINY_DEG  # attitude only

    def fraction_at(self, t_s: float) -> float:
        """How far along the path (0…1) the arm is t seconds after the segment began."""
        ramp = self._ramp
        if t_s >= self.duration_s:
            return 1.0
        if t_s <= self._wait or not ramp.length:
            return 0.0
        return ramp.distance_at((t_s - self._wait) / self._scale) / ramp.length

    def time_at_fraction(self, fraction: float) -> float:
        """Seconds after the segment began at which the arm is ``fraction`` along the path."""
        ramp = self._ramp
        if fraction >= 1.0 or not ramp.length:
            return self.duration_s if fraction >= 1.0 else self._wait
        return self._wait + self._scale * ramp.time_at(max(fraction, 0.0) * ramp.length)

    def sample(self, t_s: float) -> ArmPose:
        if t_s >= self.duration_s:
            return self.end
        if t_s <= self._wait:
            return self.start
        return self._pose_at(self.fraction_at(t_s))

    def _pose_at(self, fraction: float) -> ArmPose:
        return self.start

    # distance_to_path: observed X/Y/Z (worktable mm) or joints (deg)
    def _distance_xyz(self, p) -> tuple[float, float]:
        return _norm(_sub(p, self.end.xyz)), 0.0

    def _distance_joints(self, q) -> tuple[float, float]:
        x, y, z = self._xyz_of_joints(q)
        return self._distance_xyz((x, y, z))

    def _xyz_of_joints(self, q) -> tuple[float, float, float]:
        """Worktable X/Y/Z of joints ``q`` in this segment's frame."""
        x, y, z = self.start.kinematics.forward(q)[:3]
        ox, oy, oz = self.start.origin_mm
        return x - ox, y - oy, z - oz

    def __repr__(self) -> str:
        note = f", note={self.note!r}" if self.note else ""
        return f"<Segment {self.kind} {type(self.command).__name__} {self.duration_s:.4f} s length={self.length:.3f}{note}>"


class _StillSegment(Segment):
    __slots__ = ()

    def _distance_joints(self, q):
        return max(abs(a - b) for a, b in zip(q, self.end.joints)), 0.0


class _CartesianSegment(Segment):
    """Line or arc: position from ``_point``, attitude and E0/E1 linear in the fraction."""

    __slots__ = ("_att0", "_datt", "_e", "_de", "att_lead_deg", "ext_lead_deg")

    def __init__(self, command, kind, start, end, length):
        super().__init__(command, kind, start, end, length)
        a, b = start.cartesian, end.cartesian
        self._att0 = a[3:]
        self._datt = (_short(b[3] - a[3]), _short(b[4] - a[4]), _short(b[5] - a[5]))
        self._e = (start.e0_deg, start.e1_deg)
        self._de = (end.e0_deg - start.e0_deg, end.e1_deg - start.e1_deg)
        self.att_lead_deg = max(abs(d) for d in self._datt)
        self.ext_lead_deg = max(abs(d) for d in self._de)

    def cartesian_at(self, t_s: float) -> tuple[float, float, float, float, float, float] | None:
        """``sample(t_s).cartesian`` as a plain tuple, the same floats, where the arm is between
        the ends of the path (None at either end: ``sample`` gives ``start`` or ``end``, whose
        other half is cached).  For the simulator's status frames (one per 30 ms of a
        20-minute job): the pose's values without the pose, the ArmPose and CartesianPose objects
        that ``sample`` builds for them.  Its PWM, origin and IK hint are ``end``'s."""
        if t_s >= self.duration_s or t_s <= self._wait:
            return None
        ramp = self._ramp
        f = ramp.distance_at((t_s - self._wait) / self._scale) / ramp.length if ramp.length else 0.0
        x, y, z = self._point(f)
        a, da = self._att0, self._datt
        return (x, y, z, a[0] + da[0] * f, a[1] + da[1] * f, a[2] + da[2] * f)

    def _pose_at(self, f):
        x, y, z = self._point(f)
        a, da, end = self._att0, self._datt, self.end
        return ArmPose(
            end.kinematics, cartesian=(x, y, z, a[0] + da[0] * f, a[1] + da[1] * f, a[2] + da[2] * f),
            pwm_us=end.pwm_us, e0_deg=self._e[0] + self._de[0] * f, e1_deg=self._e[1] + self._de[1] * f,
            origin_mm=end.origin_mm, hint=end._hint,
        )


class _LineSegment(_CartesianSegment):
    __slots__ = ("_p0", "_d")

    def __init__(self, command, start, end):
        self._p0 = start.xyz
        self._d = _sub(end.xyz, self._p0)
        length = _norm(self._d)
        super().__init__(command, "line", start, end, length if length > TINY_MM else 0.0)

    def _point(self, f):
        p, d = self._p0, self._d
        return p[0] + d[0] * f, p[1] + d[1] * f, p[2] + d[2] * f

    def cartesian_at(self, t_s: float) -> tuple[float, float, float, float, float, float] | None:
        """``_CartesianSegment.cartesian_at`` with ``_point`` written in: the same floats, one
        call fewer on a status frame's way."""
        if t_s >= self.duration_s or t_s <= self._wait:
            return None
        ramp = self._ramp
        f = ramp.distance_at((t_s - self._wait) / self._scale) / ramp.length if ramp.length else 0.0
        p, d, a, da = self._p0, self._d, self._att0, self._datt
        return (p[0] + d[0] * f, p[1] + d[1] * f, p[2] + d[2] * f, a[0] + da[0] * f, a[1] + da[1] * f, a[2] + da[2] * f)

    def _distance_xyz(self, p):
        if not self.length:
            return _norm(_sub(p, self._p0)), 0.0
        # _sub, _dot, min(max(…)), _point, _sub and _norm written out, operation by operation
        # (the same floats; the streamer asks this of every position report, ~4,500 a 20-minute job)
        p0, d = self._p0, self._d
        px, py, pz = p
        u = ((px - p0[0]) * d[0] + (py - p0[1]) * d[1] + (pz - p0[2]) * d[2]) / (self.length * self.length)
        u = 0.0 if 0.0 > u else u  # max(u, 0.0): u unless 0.0 is greater (NaN stays)
        u = 1.0 if 1.0 < u else u  # min(…, 1.0)
        ex, ey, ez = px - (p0[0] + d[0] * u), py - (p0[1] + d[1] * u), pz - (p0[2] + d[2] * u)
        return math.sqrt(ex * ex + ey * ey + ez * ez), u


class _ArcSegment(_CartesianSegment):
    __slots__ = ("_arc", "_u", "_v")

    def __init__(self, command, start, end, arc: Arc):
        self._arc = arc
        self._u = _sub(start.xyz, arc.center)
        self._v = _cross(arc.normal, self._u)
        super().__init__(command, "arc", start, end, arc.length_mm)

    def _point(self, f):
        angle = self._arc.sweep_rad * f
        c, s, center, u, v = math.cos(angle), math.sin(angle), self._arc.center, self._u, self._v
        return tuple(center[i] + u[i] * c + v[i] * s for i in range(3))

    def _distance_xyz(self, p):
        arc = self._arc
        w = _sub(p, arc.center)
        along_u, along_v = _dot(w, self._u) / arc.radius_mm, _dot(w, self._v) / arc.radius_mm
        angle = math.atan2(along_v, along_u) % (2 * math.pi)
        if angle <= arc.sweep_rad:
            return math.hypot(_dot(w, arc.normal), math.hypot(along_u, along_v) - arc.radius_mm), angle / arc.sweep_rad
        to_start, to_end = _norm(_sub(p, self.start.xyz)), _norm(_sub(p, self.end.xyz))
        return (to_start, 0.0) if to_start <= to_end else (to_end, 1.0)


class _JointSegment(Segment):
    __slots__ = ("_q0", "_dq", "_e", "_de", "_polyline")

    def __init__(self, command, start, end):
        self._q0 = start.joints
        self._dq = tuple(b - a for a, b in zip(self._q0, end.joints))
        self._e = (start.e0_deg, start.e1_deg)
        self._de = (end.e0_deg - start.e0_deg, end.e1_deg - start.e1_deg)
        self._polyline = None
        lead = max(max(abs(d) for d in self._dq), max(abs(d) for d in self._de))
        super().__init__(command, "joint", start, end, lead if lead > TINY_DEG else 0.0)

    @property
    def moves_reported(self) -> bool:
        """Its joints move (its length may be E0/E1's alone, which no status reports)."""
        return max(abs(d) for d in self._dq) > TINY_DEG

    def _joints_at(self, f):
        return tuple(a + d * f for a, d in zip(self._q0, self._dq))

    def _pose_at(self, f):
        end = self.end
        return ArmPose(
            end.kinematics, joints=self._joints_at(f), pwm_us=end.pwm_us, origin_mm=end.origin_mm,
            e0_deg=self._e[0] + self._de[0] * f, e1_deg=self._e[1] + self._de[1] * f,
        )

    def _distance_joints(self, q):
        span = _dot6(self._dq, self._dq)
        u = 0.0 if span <= TINY_DEG**2 else min(max(_dot6([a - b for a, b in zip(q, self._q0)], self._dq) / span, 0.0), 1.0)
        return max(abs(a - b) for a, b in zip(q, self._joints_at(u))), u

    def _distance_xyz(self, p):
        if self._polyline is None:
            count = _FK_POLYLINE_POINTS
            self._polyline = [self._xyz_of_joints(self._joints_at(k / count)) for k in range(count + 1)]
        best = (math.inf, 0.0)
        points = self._polyline
        for k in range(len(points) - 1):
            a, d = points[k], _sub(points[k + 1], points[k])
            span = _dot(d, d)
            u = 0.0 if span <= TINY_MM**2 else min(max(_dot(_sub(p, a), d) / span, 0.0), 1.0)
            distance = _norm(_sub(p, (a[0] + d[0] * u, a[1] + d[1] * u, a[2] + d[2] * u)))
            if distance < best[0]:
                best = (distance, (k + u) / (len(points) - 1))
        return best


def _dot6(a, b):
    return sum(x * y for x, y in zip(a, b))


def distance_to_path(segment: Segment, observed: Sequence[float]) -> tuple[float, float]:
    """(distance, fraction 0…1 along the path) of an observed position from a segment's path.

    ``observed`` is X/Y/Z (3 values, worktable mm) or joints J1…J6 (6 values, deg).  The
    distance is in degrees (largest joint difference) when joints are compared with a joint or
    still segment, else in mm (joints observed on a Cartesian segment are turned into X/Y/Z by
    FK; X/Y/Z observed on a joint segment are matched against its FK trace, 16 chords).  A
    path of zero length gives fraction 0: the observation proves no progress along it.
    """
    observed = tuple(observed)
    if len(observed) == 3:
        return segment._distance_xyz(observed)
    if len(observed) == 6:
        return segment._distance_joints(observed)
    raise ValueError(f"observed must be X/Y/Z (3 values) or J1…J6 (6 values), not {len(observed)} values")


def on_path(segment: Segment, observed: Sequence[float], tolerance_mm: float = 0.2,
            tolerance_deg: float = 0.05) -> float | None:
    """The fraction along the path if ``observed`` lies on it within tolerance, else None."""
    distance, fraction = distance_to_path(segment, observed)
    in_degrees = len(observed) == 6 and segment.kind in ("joint", "still")
    return fraction if distance <= (tolerance_deg if in_degrees else tolerance_mm) else None


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
        segment = _StillSegment(command, "still", start, start)  # ArcStart, MCode, control frames
        if type(command) in MOTION_COMMANDS and type(command) is not ArcStart:  # MCode
            segment._set_timing(_NO_MOTION, wait_s=self._overhead_s)
        return segment

    # --- Cartesian ---

    def _speed(self, speed_mm_min: float, segment: Segment) -> float:
        """mm/s, clamped to the profile's maximum (noted on the segment)."""
        limit = self.profile.speed.max_linear_mm_min
        if speed_mm_min > limit:
            segment.note = f"speed {speed_mm_min:g} mm/min clamped to the profile's {limit:g} mm/min"
        return _mm_s(speed_mm_min, limit)

    def _time_cartesian(self, segment: _CartesianSegment, pieces) -> Segment:
        """How every Cartesian move is timed (``Planner.feed_s`` times a LinearMove with the
        same functions, without its segment): the path's ramp, stretched (``_stretch``) when the
        attitude or the E axes need longer; without a path, the time they need, or the PWM
        change's (``_still_ramp``)."""
        other_s = self._other_s(segment.att_lead_deg, segment.ext_lead_deg)
        if segment.length:
            ramp = _Ramp(pieces)
            return segment._set_timing(ramp, self.speed_factor * _stretch(ramp.duration, other_s), self._overhead_s)
        return segment._set_timing(self._still_ramp(other_s, segment.start.pwm_us != segment.end.pwm_us),
                                   self.speed_factor, self._overhead_s)

    def _other_s(self, att_lead_deg: float, ext_lead_deg: float) -> float:
        """Seconds the attitude and the E axes need to turn through their leads (degrees)."""
        speed = self.profile.speed
        return max(att_lead_deg / speed.attitude_deg_s, ext_lead_deg / speed.max_joint_deg_s)

    def _still_ramp(self, other_s: float, pwm_changed: bool) -> _Ramp:
        """The ramp of a Cartesian move without a path: as long as its attitude and E axes
        need (``other_s``), or as a PWM change if only that changes; one unit long."""
        if other_s <= 0 and pwm_changed:
            other_s = self.profile.timing.pwm_change_s
        return _Ramp.constant(1.0, other_s)

    def _end_cartesian(self, command, start: ArmPose, pwm_us=None) -> ArmPose:
        return ArmPose(
            self.kinematics, cartesian=(command.x_mm, command.y_mm, command.z_mm, command.b0_deg, command.b1_deg,
                                        command.w_deg),
            pwm_us=start.pwm_us if pwm_us is None else pwm_us, e0_deg=command.e0_deg, e1_deg=command.e1_deg,
            origin_mm=start.origin_mm, hint=start.known_joints,
        )

    def _plan_linear(self, command: LinearMove, start: ArmPose) -> Segment:
        end = self._end_cartesian(command, start, start.with_pwm(command.pwm_channel, command.pwm_us))
        segment = _LineSegment(command, start, end)
        v = self._speed(command.speed_mm_min, segment)
        return self._time_cartesian(segment, [(segment.length, v, v)])

    def _plan_accel(self, command: AccelLinearMove, start: ArmPose) -> Segment:
        segment = _LineSegment(command, start, self._end_cartesian(command, start))
        v1 = self._speed(command.speed1_mm_min, segment)
        v0 = min(command.speed0_mm_min, self.profile.speed.max_linear_mm_min) / 60.0
        accel = max(-self.profile.speed.max_accel_mm_s2, min(command.accel_mm_s2, self.profile.speed.max_accel_mm_s2))
        if accel == 0:
            segment.note = "acceleration 0: planned at constant speed1"
            pieces = [(segment.length, v1, v1)]
        else:
            pieces = _accel_pieces(command.mode, segment.length, accel, v1, v0)
        return self._time_cartesian(segment, pieces)

    def _plan_arc(self, command: ArcEnd, start: ArmPose, arc_start: ArcStart | None) -> Segment:
        end = self._end_cartesian(command, start, start.with_pwm(1, command.pwm_us))
        if arc_start is None:
            segment = _LineSegment(command, start, end)
            v = self._speed(command.speed_mm_min or self.profile.speed.max_linear_mm_min, segment)
            segment.note = "arc end without its arc start: planned as a straight line"
            return self._time_cartesian(segment, [(segment.length, v, v)])
        arc = arc_through(start.xyz, (arc_start.x_mm, arc_start.y_mm, arc_start.z_mm), end.xyz)
        segment = _LineSegment(command, start, end) if arc is None else _ArcSegment(command, start, end, arc)
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
        segment = _JointSegment(command, start, end)
        limit = self.profile.speed.max_joint_deg_s
        if speed_deg_s > limit:
            segment.note = f"joint speed {speed_deg_s:g} deg/s clamped to the profile's {limit:g} deg/s"
            speed_deg_s = limit
        if segment.length:
            ramp = _Ramp(_joint_pieces(segment.length, speed_deg_s, self.profile.timing.ramp_s(smoothing)))
        elif start.pwm_us != end.pwm_us:
            ramp = _Ramp.constant(1.0, self.profile.timing.pwm_change_s)
        else:
            ramp = _NO_MOTION
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
        ramp = _Ramp(_joint_pieces(lead_deg, speed_deg_s, self.profile.timing.ramp_s(smoothing)))
        return ramp.duration * self.speed_factor

    # --- the rest ---

    def _plan_delay(self, command: Delay, start: ArmPose) -> Segment:
        segment = _StillSegment(command, "still", start, start)
        return segment._set_timing(_Ramp.constant(1.0, command.delay_ms / 1000.0), 1.0, self._overhead_s)

    def _plan_origin(self, command: SetWorktableOrigin, start: ArmPose) -> Segment:
        end = start.replace(origin_mm=(command.x_mm, command.y_mm, command.z_mm))
        return _StillSegment(command, "still", start, end)


class Planner:
    """Plans a command stream in order: keeps the current pose and a pending ArcStart.

    ``feed(command)`` returns the command's segment and moves ``pose`` to its end.  An ArcStart
    is remembered for the ArcEnd that must follow it; any other command forgets it.
    ``feed_s(command)`` is ``feed(command).duration_s`` for a caller that needs the time alone
    (lint's E012 clock, issue 13): a LinearMove is then timed without building its segment or
    its end pose — ``pose`` builds that pose when it is next read, as ``feed`` would have.
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

        The move is timed with ``_time_cartesian``'s functions (``_other_s``, ``_stretch``,
        ``_still_ramp``) from its length, speed (``_mm_s``) and one constant-speed piece
        (``_piece_s``, as ``_Ramp`` times it): one rule, so the seconds are the same float
        (tests/test_lint_fastpaths.py holds the two equal).  A chain of LinearMoves keeps the
        origin and IK hint of the pose it starts from: a LinearMove's end carries its start's
        (``_end_cartesian``), and no one can read the joints of an end pose that is not built,
        so the hint stays the chain's first."""
        if type(command) is not LinearMove or not command.speed_mm_min > 0:
            return self.feed(command).duration_s
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
        else:  # the leads as _CartesianSegment measures them
            other_s = self.model._other_s(max(abs(_short(b0 - sb0)), abs(_short(b1 - sb1)), abs(_short(w - sw))),
                                          max(abs(e0 - se0), abs(e1 - se1)))
        dx, dy, dz = x - sx, y - sy, z - sz
        length = math.sqrt(dx * dx + dy * dy + dz * dz)  # _LineSegment's _norm
        if length > TINY_MM:  # _time_cartesian's path: one constant-speed piece, its _Ramp's duration
            path_s = _piece_s(length, v := _mm_s(command.speed_mm_min, max_mm_min), v)
            return overhead_s + path_s * (speed_factor * _stretch(path_s, other_s))  # as Segment._set_timing
        return overhead_s + self.model._still_ramp(other_s, spwm != pwm).duration * speed_factor

    def feed_all(self, commands) -> list[Segment]:
        return [self.feed(command) for command in commands]
