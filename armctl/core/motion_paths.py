"""The motion model's geometry: segments (a command's path and its timing) and where an observation lies on one.

Strategy: a ``Segment`` holds a path — straight line, circular arc, straight line in joint
space, or standing still — and the ``Ramp`` (armctl/core/motion_ramps.py) that times it; the
planner (armctl/core/motion.py) builds them and sets their timing.  ``sample(t)`` evaluates the
ramp and builds an ``ArmPose`` on the path; ``distance_to_path`` answers how far an observed
position (X/Y/Z or joints) lies from the path and how far along it, which is what the streamer
and the job engine read reports against.  The arc geometry (``circle_through``,
``arc_through``) is here too, for the planner and for lint.  Plain floats; no clock, no I/O.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

from .motion_pose import TINY_DEG, TINY_MM, ArmPose
from .motion_ramps import NO_MOTION, Ramp

_FK_POLYLINE_POINTS = 16  # joint segments matched against a Cartesian observation
_sqrt = math.sqrt


# --- arc geometry (also for lint) -----------------------------------------------------------------


def sub3(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross3(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm3(a):
    return math.sqrt(dot3(a, a))


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
    a, b = sub3(p0, p2), sub3(p1, p2)
    axb = cross3(a, b)
    area2 = norm3(axb)  # twice the triangle's area
    longest = max(norm3(a), norm3(b), norm3(sub3(p1, p0)))
    if longest <= tol_mm or area2 / longest <= tol_mm:  # area2 / longest = smallest altitude
        return None
    k = 1.0 / (2.0 * area2 * area2)
    m = tuple(dot3(a, a) * b[i] - dot3(b, b) * a[i] for i in range(3))
    offset = cross3(m, axb)
    center = tuple(p2[i] + offset[i] * k for i in range(3))
    normal = cross3(sub3(p1, p0), sub3(p2, p1))
    n = norm3(normal)
    return center, norm3(sub3(p0, center)), (normal[0] / n, normal[1] / n, normal[2] / n)


def arc_through(p0, p1, p2, tol_mm: float = 1e-6) -> Arc | None:
    """The arc from ``p0`` through ``p1`` to ``p2``, or None (see circle_through)."""
    circle = circle_through(p0, p1, p2, tol_mm)
    if circle is None:
        return None
    center, radius, normal = circle
    u = sub3(p0, center)
    v = cross3(normal, u)
    w = sub3(p2, center)
    sweep = math.atan2(dot3(w, v), dot3(w, u)) % (2 * math.pi)
    return Arc(center, radius, normal, sweep or 2 * math.pi)


# --- segments -------------------------------------------------------------------------------------

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
        # _set_timing(NO_MOTION) written in (a segment of every command of a run): duration 0.0 + 0.0 × 1.0
        self._ramp, self._scale, self._wait, self.duration_s = NO_MOTION, 1.0, 0.0, 0.0

    def _set_timing(self, ramp: Ramp, scale: float = 1.0, wait_s: float = 0.0) -> "Segment":
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
        # max(fraction, 0.0) without the call: fraction unless 0.0 is greater (NaN and -0.0 stay)
        return self._wait + self._scale * ramp.time_at((0.0 if 0.0 > fraction else fraction) * ramp.length)

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
        return norm3(sub3(p, self.end.xyz)), 0.0

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


class StillSegment(Segment):
    __slots__ = ()

    def _distance_joints(self, q):
        return max(abs(a - b) for a, b in zip(q, self.end.joints)), 0.0


class CartesianSegment(Segment):
    """Line or arc: position from ``_point``, attitude and E0/E1 linear in the fraction."""

    __slots__ = ("_att0", "_datt", "_e", "_de", "att_lead_deg", "ext_lead_deg")

    def __init__(self, command, kind, start, end, length):
        super().__init__(command, kind, start, end, length)
        a, b = start.cartesian, end.cartesian
        self._att0 = a[3:]
        # short_deg of each difference and the leads' max of abs, written out: the same operations
        # in the same order (the planner builds one of these for every Cartesian move of a run)
        d0, d1, d2 = (b[3] - a[3] + 180.0) % 360.0 - 180.0, (b[4] - a[4] + 180.0) % 360.0 - 180.0, \
            (b[5] - a[5] + 180.0) % 360.0 - 180.0
        self._datt = (d0, d1, d2)
        e0, e1 = start.e0_deg, start.e1_deg
        self._e = (e0, e1)
        de0, de1 = end.e0_deg - e0, end.e1_deg - e1
        self._de = (de0, de1)
        self.att_lead_deg = max(abs(d0), abs(d1), abs(d2))
        self.ext_lead_deg = max(abs(de0), abs(de1))

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


class LineSegment(CartesianSegment):
    __slots__ = ("_p0", "_d")

    def __init__(self, command, start, end):
        # start.xyz, sub3(end.xyz, p0) and norm3 written out, operation by operation (the same floats)
        p0, b = start.cartesian[:3], end.cartesian
        self._p0 = p0
        dx, dy, dz = b[0] - p0[0], b[1] - p0[1], b[2] - p0[2]
        self._d = (dx, dy, dz)
        length = _sqrt(dx * dx + dy * dy + dz * dz)
        super().__init__(command, "line", start, end, length if length > TINY_MM else 0.0)

    def _point(self, f):
        p, d = self._p0, self._d
        return p[0] + d[0] * f, p[1] + d[1] * f, p[2] + d[2] * f

    def cartesian_at(self, t_s: float) -> tuple[float, float, float, float, float, float] | None:
        """``CartesianSegment.cartesian_at`` with ``_point`` written in: the same floats, one
        call fewer on a status frame's way."""
        if t_s >= self.duration_s or t_s <= self._wait:
            return None
        ramp = self._ramp
        f = ramp.distance_at((t_s - self._wait) / self._scale) / ramp.length if ramp.length else 0.0
        p, d, a, da = self._p0, self._d, self._att0, self._datt
        return (p[0] + d[0] * f, p[1] + d[1] * f, p[2] + d[2] * f, a[0] + da[0] * f, a[1] + da[1] * f, a[2] + da[2] * f)

    def _distance_xyz(self, p):
        if not self.length:
            return norm3(sub3(p, self._p0)), 0.0
        # sub3, dot3, min(max(…)), _point, sub3 and norm3 written out, operation by operation
        # (the same floats; the streamer asks this of every position report, ~4,500 a 20-minute job)
        (p0x, p0y, p0z), (dx, dy, dz) = self._p0, self._d
        px, py, pz = p
        u = ((px - p0x) * dx + (py - p0y) * dy + (pz - p0z) * dz) / (self.length * self.length)
        u = 0.0 if 0.0 > u else u  # max(u, 0.0): u unless 0.0 is greater (NaN stays)
        u = 1.0 if 1.0 < u else u  # min(…, 1.0)
        ex, ey, ez = px - (p0x + dx * u), py - (p0y + dy * u), pz - (p0z + dz * u)
        return _sqrt(ex * ex + ey * ey + ez * ez), u


class ArcSegment(CartesianSegment):
    __slots__ = ("_arc", "_u", "_v")

    def __init__(self, command, start, end, arc: Arc):
        self._arc = arc
        self._u = sub3(start.xyz, arc.center)
        self._v = cross3(arc.normal, self._u)
        super().__init__(command, "arc", start, end, arc.length_mm)

    def _point(self, f):
        angle = self._arc.sweep_rad * f
        c, s, center, u, v = math.cos(angle), math.sin(angle), self._arc.center, self._u, self._v
        return tuple(center[i] + u[i] * c + v[i] * s for i in range(3))

    def _distance_xyz(self, p):
        arc = self._arc
        w = sub3(p, arc.center)
        along_u, along_v = dot3(w, self._u) / arc.radius_mm, dot3(w, self._v) / arc.radius_mm
        angle = math.atan2(along_v, along_u) % (2 * math.pi)
        if angle <= arc.sweep_rad:
            return math.hypot(dot3(w, arc.normal), math.hypot(along_u, along_v) - arc.radius_mm), angle / arc.sweep_rad
        to_start, to_end = norm3(sub3(p, self.start.xyz)), norm3(sub3(p, self.end.xyz))
        return (to_start, 0.0) if to_start <= to_end else (to_end, 1.0)


class JointSegment(Segment):
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
        span = dot6(self._dq, self._dq)
        u = 0.0 if span <= TINY_DEG**2 else min(max(dot6([a - b for a, b in zip(q, self._q0)], self._dq) / span, 0.0), 1.0)
        return max(abs(a - b) for a, b in zip(q, self._joints_at(u))), u

    def _distance_xyz(self, p):
        if self._polyline is None:
            count = _FK_POLYLINE_POINTS
            self._polyline = [self._xyz_of_joints(self._joints_at(k / count)) for k in range(count + 1)]
        best = (math.inf, 0.0)
        points = self._polyline
        for k in range(len(points) - 1):
            a, d = points[k], sub3(points[k + 1], points[k])
            span = dot3(d, d)
            u = 0.0 if span <= TINY_MM**2 else min(max(dot3(sub3(p, a), d) / span, 0.0), 1.0)
            distance = norm3(sub3(p, (a[0] + d[0] * u, a[1] + d[1] * u, a[2] + d[2] * u)))
            if distance < best[0]:
                best = (distance, (k + u) / (len(points) - 1))
        return best


def dot6(a, b):
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
