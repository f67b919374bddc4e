"""Forward and inverse kinematics of the 6-axis arm: closed form, spherical wrist.

Strategy: the arm is a base yaw (J1), a shoulder and an elbow pitching in one vertical plane
(J2, J3), then a wrist of three intersecting axes (J4 roll, J5 pitch, J6 roll).  The first
three joints place the wrist centre (a two-link problem in the arm's plane), the last three
orient the tool (an X-Y-X Euler decomposition).  ``inverse`` enumerates the up to eight
closed-form solutions (front/back, elbow up/down, wrist flip), moves each angle by whole
turns towards the hint, drops those outside the joint limits and returns the one nearest the
hint.  Pure functions of plain floats and tuples; no I/O, stdlib only.  For lint, which asks
"is there a solution?" of every target, ``has_solution`` answers without choosing the best one,
``ball_has_solution`` proves a whole ball of targets at once (interval bounds on each joint),
and ``SolvableCells`` keeps such proofs per grid cube: sound shortcuts, never approximations.

Frames and conventions (the vendor publishes none; these are armctl's, one place to change):

- Robot frame: origin on the base axis in the mounting plane, +Z up, +X forward (the arm's
  direction at J1 = 0), +Y to the left; right-handed; millimetres.  (The worktable frame the
  protocol reports X/Y/Z in is this frame shifted by the worktable origin; see motion.py.)
- Joint zeros and signs, degrees:
  J1 base yaw about +Z, positive counter-clockwise seen from above.
  J2 shoulder: 0 = upper arm vertical; positive leans it forward (rotation about the arm
  plane's +Y axis, so J2, J3 and J5 all pitch "forward and down" when positive).
  J3 elbow: 0 = forearm perpendicular to the upper arm (horizontal when J2 = 0).
  J4 forearm roll about the forearm axis.  J5 wrist pitch: 0 = flange in line with the
  forearm.  J6 flange roll.  So J2 = J3 = 0, J5 = 90 points the tool straight down.
- Links (``Links``, mm): base_height (shoulder axis above the mounting plane), shoulder_offset
  (shoulder axis ahead of the base axis), upper_arm (shoulder → elbow), elbow_offset (the
  forearm axis sits this far from the elbow axis, along the upper arm when J3 = 0), forearm
  (elbow → wrist centre along the forearm), tool (wrist centre → tool point along the flange).
- Attitude B0, B1, W (deg) = roll, pitch, yaw of the tool frame relative to the robot frame:
  R = Rz(W) · Ry(B1) · Rx(B0) — rotate about the fixed X axis by B0, then about the fixed Y by
  B1, then about the fixed Z by W.  Tool frame: z = approach (out of the flange); at all-zero
  joints z points along +X and x points up.  Hence B0 = 180, B1 = 0, W = 0 is "tool straight
  down, tool x along robot +X", and W then turns the tool about the vertical.  The triple is
  singular at B1 = ±90 (tool x axis vertical); there W is reported as 0.  ``forward`` reports
  angles in (−180, 180].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import NamedTuple, Sequence

from .errors import ArmctlError

JOINT_COUNT = 6
_EPS = 1e-9


class Unreachable(ArmctlError, ValueError):
    """A Cartesian pose the arm cannot take (out of reach, or only outside its joint limits)."""


class CartesianPose(NamedTuple):
    """Tool point (mm) and attitude (deg, see the module docstring) in one frame."""

    x_mm: float
    y_mm: float
    z_mm: float
    b0_deg: float
    b1_deg: float
    w_deg: float


@dataclass(frozen=True)
class Links:
    """Link lengths of the arm in mm (see the module docstring for where each one sits)."""

    base_height_mm: float
    shoulder_offset_mm: float
    upper_arm_mm: float
    elbow_offset_mm: float
    forearm_mm: float
    tool_mm: float


# --- rotations as row-major 9-tuples -----------------------------------------------------------


def _mul(a, b):
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (
        a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
        a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
        a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8,
    )


def _rpy_matrix(b0, b1, w):
    """Rz(w)·Ry(b1)·Rx(b0), radians."""
    ca, sa, cb, sb, cw, sw = math.cos(b0), math.sin(b0), math.cos(b1), math.sin(b1), math.cos(w), math.sin(w)
    return (
        cw * cb, cw * sb * sa - sw * ca, cw * sb * ca + sw * sa,
        sw * cb, sw * sb * sa + cw * ca, sw * sb * ca - cw * sa,
        -sb, cb * sa, cb * ca,
    )


def _rpy_of(r):
    """(b0, b1, w) radians of a rotation, w = 0 at the B1 = ±90° singularity."""
    cb = math.hypot(r[0], r[3])
    b1 = math.atan2(-r[6], cb)
    if cb < 1e-9:
        return math.atan2(-r[5], r[4]), b1, 0.0
    return math.atan2(r[7], r[8]), b1, math.atan2(r[3], r[0])


def _xyx(a, b, c):
    """Rx(a)·Ry(b)·Rx(c), radians: the wrist's rotation relative to the forearm."""
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return (
        cb, sb * sc, sb * cc,
        sa * sb, ca * cc - sa * cb * sc, -ca * sc - sa * cb * cc,
        -ca * sb, sa * cc + ca * cb * sc, -sa * sc + ca * cb * cc,
    )


def _arm(j1, t):
    """Rz(j1)·Ry(t): the forearm frame (t = J2 + J3)."""
    c1, s1, ct, st = math.cos(j1), math.sin(j1), math.cos(t), math.sin(t)
    return (c1 * ct, -s1, c1 * st, s1 * ct, c1, s1 * st, -st, 0.0, ct)


def _tool_from_flange(r):
    """Tool frame = flange frame · F, F = Ry(−90)·Rx(180): tool x = flange z, y = −y, z = flange x."""
    return (r[2], -r[1], r[0], r[5], -r[4], r[3], r[8], -r[7], r[6])


_flange_from_tool = _tool_from_flange  # F is its own inverse


def rotation_matrix(b0_deg: float, b1_deg: float, w_deg: float) -> tuple[float, ...]:
    """The attitude as a row-major 3×3 rotation matrix (for comparing attitudes robustly)."""
    return _rpy_matrix(math.radians(b0_deg), math.radians(b1_deg), math.radians(w_deg))


def wrap_deg(angle: float) -> float:
    """An angle in (−180, 180]."""
    angle = math.fmod(angle, 360.0)
    if angle > 180.0:
        angle -= 360.0
    elif angle <= -180.0:
        angle += 360.0
    return angle


# --- forward ----------------------------------------------------------------------------------


def forward(joints_deg: Sequence[float], links: Links) -> CartesianPose:
    """Tool pose in the robot frame for joint angles J1…J6 (deg)."""
    j1, j2, j3, j4, j5, j6 = (math.radians(j) for j in joints_deg)
    t = j2 + j3
    ct, st = math.cos(t), math.sin(t)
    radial = (
        links.shoulder_offset_mm + links.upper_arm_mm * math.sin(j2) + links.forearm_mm * ct + links.elbow_offset_mm * st
    )
    z = links.base_height_mm + links.upper_arm_mm * math.cos(j2) - links.forearm_mm * st + links.elbow_offset_mm * ct
    flange = _mul(_arm(j1, t), _xyx(j4, j5, j6))
    d6 = links.tool_mm
    x = radial * math.cos(j1) + d6 * flange[0]
    y = radial * math.sin(j1) + d6 * flange[3]
    z = z + d6 * flange[6]
    b0, b1, w = _rpy_of(_tool_from_flange(flange))
    return CartesianPose(x, y, z, wrap_deg(math.degrees(b0)), wrap_deg(math.degrees(b1)), wrap_deg(math.degrees(w)))


# --- inverse ----------------------------------------------------------------------------------
#
# One solver, ``_solve``, written out flat (no generators, no matrix tuples): ``solutions``,
# ``inverse`` (the simulator asks it of every joints status frame, issue 11) and
# ``has_solution`` (lint asks it of every target, issue 13) are three ways of walking its
# solutions, so the IK math exists once.

_EVERY, _FIRST, _NEAREST = "every", "first", "nearest"  # what ``_solve`` does with each solution
_NO_LIMITS = (None,) * JOINT_COUNT
_RAD_TO_DEG = 180.0 / math.pi  # x * this is math.degrees(x) bit for bit (CPython's own constant)
# the solver's functions and constants as module globals (one look-up each, not two)
_cos, _sin, _atan2, _acos, _hypot, _radians = math.cos, math.sin, math.atan2, math.acos, math.hypot, math.radians
_PI, _HALF_PI, _INF = math.pi, math.pi / 2, math.inf


def solutions(pose: Sequence[float], links: Links, near: Sequence[float] | None = None) -> list[tuple[float, ...]]:
    """Every closed-form solution (deg, each angle in (−180, 180]) for a robot-frame pose.

    In a fixed order: J1 towards the wrist centre then away from it, each with both elbows,
    each with both wrist flips.  At a singularity the free angle is taken from ``near`` (J1
    when the wrist centre is on the base axis, J4 when J5 = 0).  An empty list means the pose
    is out of reach.
    """
    return _solve(pose, _prepared(links, _NO_LIMITS), near or (0.0,) * JOINT_COUNT, _EVERY)[0]


@lru_cache(maxsize=256)
def _flange_of(b0_deg: float, b1_deg: float, w_deg: float):
    """The flange rotation for a tool attitude: scripts keep one attitude for many moves."""
    return _flange_from_tool(_rpy_matrix(math.radians(b0_deg), math.radians(b1_deg), math.radians(w_deg)))


def _fit(angle: float, hint: float, limits: tuple[float, float] | None) -> float | None:
    """``angle`` moved by whole turns towards ``hint``, inside ``limits`` if given (else None).

    Off by at most a whole number of turns plus 1e-6 (a candidate that far outside the limits
    is moved onto them) plus float rounding: ``_fitted`` relies on it."""
    base = angle + 360.0 * round((hint - angle) / 360.0)
    if limits is None:
        return base
    low, high = limits
    if low <= base <= high:
        return base
    other = base - 360.0 if base > hint else base + 360.0
    for candidate in (base, other, 2 * base - other):
        if low - 1e-6 <= candidate <= high + 1e-6:
            return min(max(candidate, low), high)
    return None


_FAR_MARGIN_DEG = 1e-5  # above _fit's 1e-6 and any rounding of angles below 1e6°, far below a joint's meaning


def _fitted(angle: float, hint: float, limits: tuple[float, float] | None, cost: float = 0.0,
            bound: float = math.inf) -> float | None:
    """``_fit(wrap_deg(angle), hint, limits)``, ``angle`` in degrees, sooner in the common case;
    or None when that answer cannot bring a solution's ``cost`` so far below ``bound``.

    An angle already in (−180, 180] is its own wrap, and one inside the limits and less than
    half a turn from the hint is ``_fit``'s own answer: ``round`` of a ratio below one half is
    0, so ``_fit`` returns ``angle + 0.0`` (the ``+ 0.0`` keeps its sign of zero).  ``_solve``
    makes that first test inline and calls this for the rest.

    ``bound`` (``_solve``'s _NEAREST, once it has a best: its cost): ``_fit``'s answer is the
    angle plus whole turns, give or take 1e-6, so its distance from the hint is at least the
    angles' distance round the circle less ``_FAR_MARGIN_DEG``; when even that makes ``cost``
    + its square reach ``bound``, the solution cannot win (every cost term is >= 0 and float
    sums and squares are monotonic) and ``_fit`` is not asked (a None: the solution is
    dropped, as it would be)."""
    if not -180.0 < angle <= 180.0:
        angle = wrap_deg(angle)
    if limits is not None:
        low, high = limits
        if low <= angle <= high and -180.0 < hint - angle < 180.0:
            return angle + 0.0
    if bound < math.inf and -1e6 < hint < 1e6:
        far = abs(hint - angle) % 360.0
        if far > 180.0:
            far = 360.0 - far
        far -= _FAR_MARGIN_DEG
        if far > 0.0 and cost + far * far >= bound:
            return None
    return _fit(angle, hint, limits)


_PREPARED: dict = {}  # (id(links), id(limits)) → _prepared's answer, holding both objects
_PREPARED_MAX = 64


def _prepared(links, limits):
    """The solver's constants for ``links`` and ``limits``, computed once per pair of objects:
    (links, limits, d6, a2, reach, gamma, base height, shoulder offset, a2², reach², 2·a2·reach,
    then low and high of each joint — +inf and −inf for a joint without limits, so that the
    inline first test of ``_fitted`` never passes and ``_fitted`` itself answers).  Kept by
    identity (the entry holds both objects, so an id is not reused while it is kept): hashing a
    Links costs about what the whole look-up saves; at most ``_PREPARED_MAX`` pairs."""
    entry = _PREPARED.get((id(links), id(limits)))
    if entry is not None and entry[0] is links and entry[1] is limits:
        return entry
    if len(_PREPARED) >= _PREPARED_MAX:
        _PREPARED.clear()
    a2, a3, d4 = links.upper_arm_mm, links.elbow_offset_mm, links.forearm_mm
    reach = math.hypot(d4, a3)
    bounds = []
    for pair in limits:
        bounds += (math.inf, -math.inf) if pair is None else tuple(pair)
    entry = (links, limits, links.tool_mm, a2, reach, math.atan2(a3, d4), links.base_height_mm,
             links.shoulder_offset_mm, a2 * a2, reach * reach, 2 * a2 * reach, *bounds)
    _PREPARED[id(links), id(limits)] = entry
    return entry


def _solve(pose, prepared, near, mode):
    """The closed-form solutions of ``pose`` (front/back, elbow up/down, wrist flip), walked
    in ``solutions``' order and, unless ``mode`` is _EVERY, fitted joint by joint by
    ``_fitted`` (whole turns towards ``near``, inside the limits ``prepared`` was made for by
    ``_prepared``: six pairs or six Nones).

    Returns (answer, worst, reachable): reachable says whether any arm placement exists;
    worst = (k, angle) is the first joint found outside its limits (None if none).
      _EVERY    answer = the list of every solution, unfitted (``solutions``); limits unused.
      _FIRST    answer = the first solution that fits (None if none): it stops there
                (``has_solution``: the order cannot change a yes-or-no answer).
      _NEAREST  answer = the fitted solution nearest ``near`` (sum of squares in joint order;
                the first of equals), or None (``inverse``).
    _NEAREST costs each solution joint by joint and drops it as soon as its cost reaches the
    best's (every term is >= 0; _FIRST keeps no costs); once it has a best, a J1 whose cost
    alone reaches it drops that side before its arm is solved (worst and reachable no longer
    matter then).  The arm's three joints are fitted once for both wrist flips: an arm
    placement whose J1, J2 or J3 do not fit tries no wrist, and J1 is the same for both elbows.

    Flat for speed (the simulator asks ``inverse`` of every joints status frame, lint
    ``has_solution`` of every target): the constants of the links and limits come from
    ``_prepared``, and ``_fitted`` is written out for each joint — its first test, which also
    holds after the wrap (``_fit`` of an angle in the limits and less than half a turn from the
    hint is that angle + 0.0), then ``_fit`` itself.  The arithmetic is the enumeration's, bit
    for bit: each wrist matrix entry is the sum ``_mul(arm^T, flange)`` forms, with arm =
    ``_arm(j1, t)`` (tests/test_ik_flat.py holds all three modes to the enumeration,
    tests/ik_reference.py)."""
    x, y, z, b0, b1, w = pose
    f0, f1, f2, f3, f4, f5, f6, f7, f8 = _flange_of(b0, b1, w)
    (_, limits, d6, a2, reach, gamma, base_height, shoulder, a2a2, reach2, twice_a2_reach,
     lo1, hi1, lo2, hi2, lo3, hi3, lo4, hi4, lo5, hi5, lo6, hi6) = prepared
    wx, wy, wz = x - d6 * f0, y - d6 * f3, z - d6 * f6
    if _hypot(wx, wy) < 1e-9:
        yaw = _radians(near[0])  # on the base axis J1 is free: the hint's
    else:
        yaw = _atan2(wy, wx)
    h1, h2, h3, h4, h5, h6 = near
    l1, l2, l3, l4, l5, l6 = limits
    every, fitting, nearest = mode is _EVERY, mode is not _EVERY, mode is _NEAREST  # _FIRST keeps no costs
    found = [] if every else None
    best, best_cost, worst, reachable = None, _INF, None, False
    cost1 = cost2 = arm_cost = cost = 0.0  # _FIRST keeps them so (its bound stays inf)
    v = wz - base_height
    for j1 in (yaw, yaw + _PI):
        deg1 = j1 * _RAD_TO_DEG
        if fitting:
            a = deg1
            if -180.0 < a <= 180.0 and lo1 <= a <= hi1 and -180.0 < h1 - a < 180.0:
                q1 = a + 0.0
            else:
                q1 = _fitted(a, h1, l1, 0.0, best_cost)
            if nearest:
                if q1 is not None:
                    cost1 = (q1 - h1) ** 2
                if best is not None and (q1 is None or not cost1 < best_cost):
                    continue  # this side cannot beat the best: worst and reachable are moot now
        c1, s1 = _cos(j1), _sin(j1)
        u = wx * c1 + wy * s1 - shoulder
        cos_d = (u * u + v * v - a2a2 - reach2) / twice_a2_reach
        if abs(cos_d) > 1 + 1e-9:
            continue  # out of reach this way round
        reachable = True
        if fitting and q1 is None:
            if worst is None:
                worst = (0, wrap_deg(deg1))
            continue  # J1 is the same for both elbows
        cos_d = cos_d if cos_d < 1.0 else 1.0  # max(-1.0, min(1.0, cos_d)), NaN to 1.0 as they do, without the calls
        cos_d = cos_d if cos_d > -1.0 else -1.0
        base = _atan2(v, u)
        elbow = _acos(cos_d)
        for delta in {elbow, -elbow}:
            if nearest and not cost1 < best_cost:
                continue
            alpha = base + _atan2(reach * _sin(delta), a2 + reach * _cos(delta))
            j2 = _HALF_PI - alpha
            t = gamma - (alpha - delta)  # J2 + J3
            deg2, deg3 = j2 * _RAD_TO_DEG, (t - j2) * _RAD_TO_DEG
            if fitting:
                a = deg2
                if -180.0 < a <= 180.0 and lo2 <= a <= hi2 and -180.0 < h2 - a < 180.0:
                    q2 = a + 0.0
                else:
                    q2 = _fitted(a, h2, l2, cost1, best_cost)
                if q2 is None:
                    if worst is None:
                        worst = (1, wrap_deg(deg2))
                    continue
                if nearest:
                    cost2 = cost1 + (q2 - h2) ** 2
                    if not cost2 < best_cost:
                        continue
                a = deg3
                if -180.0 < a <= 180.0 and lo3 <= a <= hi3 and -180.0 < h3 - a < 180.0:
                    q3 = a + 0.0
                else:
                    q3 = _fitted(a, h3, l3, cost2, best_cost)
                if q3 is None:
                    if worst is None:
                        worst = (2, wrap_deg(deg3))
                    continue  # neither wrist flip can help
                if nearest:
                    arm_cost = cost2 + (q3 - h3) ** 2
                    if not arm_cost < best_cost:
                        continue
            # The wrist: Rx(J4)·Ry(J5)·Rx(J6) = arm^T · flange, only the entries it reads
            ct, st = _cos(t), _sin(t)
            r0, r1, r2 = c1 * ct, s1 * ct, -st  # arm^T's rows: arm[0], arm[3], arm[6]
            r3, r4 = -s1, c1  # arm[1], arm[4] (arm[7] = 0.0, kept in the sums for their sign of zero)
            r6, r7, r8 = c1 * st, s1 * st, ct  # arm[2], arm[5], arm[8]
            m0 = r0 * f0 + r1 * f3 + r2 * f6
            j5 = _acos((m0 if m0 > -1.0 else -1.0) if m0 < 1.0 else 1.0)  # max(-1.0, min(1.0, m0))
            if _sin(j5) < 1e-7:  # J5 = 0 or 180: only J4 ± J6 is fixed, J4 is the hint's
                near_j4 = _radians(h4)
                m4 = r3 * f1 + r4 * f4 + 0.0 * f7
                m7 = r6 * f1 + r7 * f4 + r8 * f7
                if m0 > 0:
                    wrists = ((near_j4, 0.0, _atan2(m7, m4) - near_j4),)
                else:
                    wrists = ((near_j4, _PI, near_j4 - _atan2(m7, m4)),)
            else:
                m1 = r0 * f1 + r1 * f4 + r2 * f7
                m2 = r0 * f2 + r1 * f5 + r2 * f8
                m3 = r3 * f0 + r4 * f3 + 0.0 * f6
                m6 = r6 * f0 + r7 * f3 + r8 * f6
                j4, j6 = _atan2(m3, -m6), _atan2(m1, m2)
                wrists = ((j4, j5, j6), (j4 + _PI, -j5, j6 + _PI))
            for j4, j5, j6 in wrists:
                deg4, deg5, deg6 = j4 * _RAD_TO_DEG, j5 * _RAD_TO_DEG, j6 * _RAD_TO_DEG
                if every:
                    found.append(tuple(wrap_deg(a) for a in (deg1, deg2, deg3, deg4, deg5, deg6)))
                    continue
                a = deg4
                if -180.0 < a <= 180.0 and lo4 <= a <= hi4 and -180.0 < h4 - a < 180.0:
                    q4 = a + 0.0
                else:
                    q4 = _fitted(a, h4, l4, arm_cost, best_cost)
                if q4 is None:
                    if worst is None:
                        worst = (3, wrap_deg(deg4))
                    continue
                if nearest:
                    cost = arm_cost + (q4 - h4) ** 2
                    if not cost < best_cost:
                        continue
                a = deg5
                if -180.0 < a <= 180.0 and lo5 <= a <= hi5 and -180.0 < h5 - a < 180.0:
                    q5 = a + 0.0
                else:
                    q5 = _fitted(a, h5, l5, cost, best_cost)
                if q5 is None:
                    if worst is None:
                        worst = (4, wrap_deg(deg5))
                    continue
                if nearest:
                    cost += (q5 - h5) ** 2
                    if not cost < best_cost:
                        continue
                a = deg6
                if -180.0 < a <= 180.0 and lo6 <= a <= hi6 and -180.0 < h6 - a < 180.0:
                    q6 = a + 0.0
                else:
                    q6 = _fitted(a, h6, l6, cost, best_cost)
                if q6 is None:
                    if worst is None:
                        worst = (5, wrap_deg(deg6))
                    continue
                if not nearest:
                    return (q1, q2, q3, q4, q5, q6), worst, True  # _FIRST: this one fits
                cost += (q6 - h6) ** 2
                if cost < best_cost:
                    best, best_cost = (q1, q2, q3, q4, q5, q6), cost
    return (found if every else best), worst, reachable


def inverse(
    pose: Sequence[float],
    links: Links,
    near: Sequence[float] | None = None,
    limits: Sequence[tuple[float, float]] | None = None,
) -> tuple[float, ...]:
    """Joint angles (deg) reaching the robot-frame ``pose``, nearest ``near`` (default all 0).

    With ``limits`` (six (min, max) pairs) only solutions inside them count.  Raises
    Unreachable naming the reason.
    """
    near = tuple(near) if near is not None else (0.0,) * JOINT_COUNT
    best, worst, reachable = _solve(pose, _prepared(links, _NO_LIMITS if limits is None else limits), near, _NEAREST)
    if not reachable:
        raise Unreachable(f"pose X{pose[0]:.1f} Y{pose[1]:.1f} Z{pose[2]:.1f} is out of the arm's reach")
    if best is None:
        k, angle = worst
        low, high = limits[k]
        raise Unreachable(
            f"pose X{pose[0]:.1f} Y{pose[1]:.1f} Z{pose[2]:.1f} needs J{k + 1} = {angle:.1f}°,"
            f" outside its limits {low:g}…{high:g}°"
        )
    return best


def has_solution(
    pose: Sequence[float], links: Links, near: Sequence[float], limits: Sequence[tuple[float, float]],
) -> bool:
    """Whether ``inverse(pose, links, near, limits)`` returns rather than raising Unreachable.

    The same solver, stopped at the first solution that fits: lint asks this of every target
    (issue 13), and only a pose that fails needs ``inverse`` again, for its message."""
    return _solve(pose, _prepared(links, limits), near, _FIRST)[0] is not None


# --- whole regions at once (lint) -------------------------------------------------------------

_PROOF_MARGIN_DEG = 1e-6  # far above the rounding of any angle below, far below any limit's meaning
_PROOF_MARGIN_MM = 1e-3  # distance kept from the singularities (base axis, arm stretched or folded)


def ball_has_solution(
    pose: Sequence[float], radius_mm: float, links: Links, near: Sequence[float],
    limits: Sequence[tuple[float, float]],
) -> bool:
    """True only if ``has_solution`` is True for every pose within ``radius_mm`` of ``pose``'s
    point with ``pose``'s attitude; False means "not proven" (the caller asks ``has_solution``).

    The proof: one branch of the closed form (front or back, elbow sign, wrist flip) fits its
    limits with room to spare at the centre, and no point of the ball can move a joint by more
    than that room.  The wrist centre moves with the tool point (same attitude), so it stays
    within ``radius_mm`` of the centre's.  Then, exactly: J1 = the bearing of the wrist centre
    turns by at most asin(ρ / r) (r its distance from the base axis); in the arm's plane the
    point (u, v) stays within ρ, so its bearing φ turns by at most asin(ρ / d) and its distance
    d stays in [d − ρ, d + ρ]; the elbow angle δ and the shoulder's triangle angle β are
    monotonic in d on that interval (β only where d² does not cross a2² − R², checked), so
    their extremes are at its ends; J2 = π/2 − φ − β, J3 = γ + δ − π/2.  The forearm frame
    Rz(J1)·Ry(J2 + J3) turns by at most θ = ΔJ1 + Δ(J2 + J3), so each column and row of the
    wrist matrix turns by at most θ: J5 (their angle from x) by θ, J4 and J6 (their bearings
    about x) by asin(sin θ / sin J5) while θ < J5 < π − θ.  A joint whose whole interval lies
    inside its limits, within half a turn of the hint and away from ±180 fits for every point
    exactly as ``_fitted`` decides it.  Float rounding (1e-13 degrees) is far inside the
    margins."""
    x, y, z, b0, b1, w = pose
    rho = float(radius_mm)
    f = _flange_of(b0, b1, w)
    d6 = links.tool_mm
    wx, wy, wz = x - d6 * f[0], y - d6 * f[3], z - d6 * f[6]
    r = math.hypot(wx, wy)
    if not r - rho > _PROOF_MARGIN_MM:
        return False
    a2, a3, d4 = links.upper_arm_mm, links.elbow_offset_mm, links.forearm_mm
    reach = math.hypot(d4, a3)
    gamma = math.atan2(a3, d4)
    v = wz - links.base_height_mm
    dj1 = math.asin(rho / r)
    yaw = math.atan2(wy, wx)
    for j1, u in ((yaw, r - links.shoulder_offset_mm), (yaw + math.pi, -r - links.shoulder_offset_mm)):
        if not _interval_fits(j1, dj1, near[0], limits[0]):
            continue
        d = math.hypot(u, v)
        d_low, d_high = d - rho, d + rho
        if not (d_low - _PROOF_MARGIN_MM > abs(a2 - reach) and d_high + _PROOF_MARGIN_MM < a2 + reach):
            continue  # the ball may reach a stretched or folded arm
        critical = a2 * a2 - reach * reach  # β is monotonic in d where d² does not cross this
        if d_low * d_low <= critical <= d_high * d_high:
            continue
        phi = math.atan2(v, u)
        dphi = math.asin(rho / d)
        c1, s1 = math.cos(j1), math.sin(j1)
        for sign in (1.0, -1.0):
            deltas = [sign * _elbow(dist, a2, reach) for dist in (d_low, d, d_high)]
            betas = [math.atan2(reach * math.sin(dl), a2 + reach * math.cos(dl)) for dl in deltas]
            delta_c, beta_c = deltas[1], betas[1]
            dbeta = max(abs(b - beta_c) for b in betas)
            ddelta = max(abs(dl - delta_c) for dl in deltas)
            j2 = math.pi / 2 - (phi + beta_c)
            j3 = gamma + delta_c - math.pi / 2
            if not (_interval_fits(j2, dphi + dbeta, near[1], limits[1])
                    and _interval_fits(j3, ddelta, near[2], limits[2])):
                continue
            t = j2 + j3
            theta = dj1 + dphi + dbeta + ddelta  # t = γ − φ − β + δ
            ct, st = math.cos(t), math.sin(t)
            arm_t = (c1 * ct, s1 * ct, -st, -s1, c1, 0.0, c1 * st, s1 * st, ct)
            m = _mul(arm_t, f)
            j5 = math.acos(max(-1.0, min(1.0, m[0])))
            if not (theta + _PROOF_MARGIN_DEG < j5 < math.pi - theta - _PROOF_MARGIN_DEG):
                continue  # near the wrist singularity J4 and J6 may turn without bound
            dj46 = math.asin(min(1.0, math.sin(theta) / math.sin(j5 - theta if j5 <= math.pi / 2 else j5 + theta)))
            j4, j6 = math.atan2(m[3], -m[6]), math.atan2(m[1], m[2])
            for wrist in ((j4, j5, j6), (j4 + math.pi, -j5, j6 + math.pi)):
                if (_interval_fits(wrist[0], dj46, near[3], limits[3]) and _interval_fits(wrist[1], theta, near[4], limits[4])
                        and _interval_fits(wrist[2], dj46, near[5], limits[5])):
                    return True
    return False


def _elbow(distance: float, a2: float, reach: float) -> float:
    """The elbow angle δ ≥ 0 (radians) at which shoulder and wrist centre are ``distance`` apart."""
    return math.acos(max(-1.0, min(1.0, (distance * distance - a2 * a2 - reach * reach) / (2 * a2 * reach))))


def _interval_fits(angle_rad: float, deviation_rad: float, hint: float, limits: tuple[float, float]) -> bool:
    """Whether every angle within ``deviation_rad`` of ``angle_rad`` passes ``_fitted``'s first
    test (inside the limits, less than half a turn from the hint), with no wrap at ±180 between."""
    angle = wrap_deg(math.degrees(angle_rad))
    spread = math.degrees(deviation_rad) * (1 + 1e-9) + _PROOF_MARGIN_DEG
    low, high = angle - spread, angle + spread
    return (-180.0 < low and high < 180.0 and limits[0] <= low and high <= limits[1]
            and -180.0 < hint - high and hint - low < 180.0)


class SolvableCells:
    """``has_solution`` for many poses of one arm, answered per grid cell where it can be (lint).

    Space is cut into cubes of ``cell_mm``; the first pose that falls in a cube (with a given
    attitude and hint) asks ``ball_has_solution`` once for the ball around the cube's centre
    that holds the whole cube — and, given the profile's workspace ``box``, whether the whole
    cube lies inside the box and the reach radius (``box_problem`` is None for all of it).  A
    proven cube answers True for every later pose in it at the cost of a dictionary look-up;
    an unproven one (near a limit, the edge of the reach or a singularity) sends each pose to
    ``has_solution`` (and ``box_problem``).  Sound, never approximate: a cube says True only
    when every pose in it passes.  At most ``max_cells`` cubes are kept (the table starts
    again when full), so memory is flat whatever the script."""

    def __init__(self, links: Links, limits: Sequence[tuple[float, float]], box=None, cell_mm: float = 16.0,
                 max_cells: int = 16384) -> None:
        self.links, self.limits, self.box = links, tuple(tuple(pair) for pair in limits), box
        self.cell_mm, self.max_cells = float(cell_mm), max_cells
        # a pose just outside its cube (floor's rounding) is still inside the ball, and the box
        self._slack_mm = 1e-6
        self._radius_mm = self.cell_mm * math.sqrt(3.0) / 2.0 * (1 + 1e-9) + self._slack_mm
        # (b0, b1, w, near) → {(i, j, k) → proven}: a script keeps one attitude and hint for
        # many lines, so the last group is found again by comparing, without hashing them
        self._groups: dict = {}
        self._count = 0
        self._last = None  # (b0, b1, w, near, cells) of the last pose

    def proven(self, pose: Sequence[float], near: Sequence[float]) -> bool:
        """True when ``pose``'s cube is proven (so ``__call__`` is True); False: not known."""
        x, y, z, b0, b1, w = pose
        last = self._last
        if last is not None and last[3] is near and last[0] == b0 and last[1] == b1 and last[2] == w:
            cells = last[4]  # ``near`` is the same tuple (immutable), so the same group
        else:
            near = near if type(near) is tuple else tuple(near)
            cells = self._groups.setdefault((b0, b1, w, near), {})
            self._last = (b0, b1, w, near, cells)
        size = self.cell_mm
        key = (math.floor(x / size), math.floor(y / size), math.floor(z / size))
        proven = cells.get(key)
        if proven is None:
            if self._count >= self.max_cells:
                self._groups.clear()
                self._count = 0
                cells = self._groups[b0, b1, w, near] = {}
                self._last = (b0, b1, w, near, cells)
            self._count += 1
            proven = cells[key] = self._prove(key, (b0, b1, w), near)
        return proven

    def __call__(self, pose: Sequence[float], near: Sequence[float]) -> bool:
        """``box_problem(pose[:3], box) is None and has_solution(pose, links, near, limits)``
        (without a box, ``has_solution`` alone)."""
        if self.proven(pose, near):
            return True
        if self.box is not None and box_problem(pose[:3], self.box) is not None:
            return False
        return has_solution(pose, self.links, near, self.limits)

    def _prove(self, key, attitude, near) -> bool:
        i, j, k = key
        b0, b1, w = attitude
        size, slack = self.cell_mm, self._slack_mm
        if self.box is not None:
            corners = [(n * size - slack, (n + 1) * size + slack) for n in (i, j, k)]
            for (low, high), (box_low, box_high) in zip(corners, (self.box.x_mm, self.box.y_mm, self.box.z_mm)):
                if not (box_low < low and high < box_high):
                    return False
            far = [max(abs(low), abs(high)) for low, high in corners]
            if not math.sqrt(far[0] * far[0] + far[1] * far[1] + far[2] * far[2]) < self.box.reach_mm - slack:
                return False
        centre = ((i + 0.5) * size, (j + 0.5) * size, (k + 0.5) * size, b0, b1, w)
        return ball_has_solution(centre, self._radius_mm, self.links, near, self.limits)


@dataclass(frozen=True)
class Kinematics:
    """Links, joint limits and a home pose (the default IK hint) bundled for repeated use."""

    links: Links
    limits: tuple[tuple[float, float], ...] | None = None
    home: tuple[float, ...] = (0.0,) * JOINT_COUNT

    def forward(self, joints_deg: Sequence[float]) -> CartesianPose:
        return forward(joints_deg, self.links)

    def inverse(self, pose: Sequence[float], near: Sequence[float] | None = None, respect_limits: bool = True):
        return inverse(pose, self.links, self.home if near is None else near, self.limits if respect_limits else None)

    @cached_property
    def _within_limits(self):
        """The solver's constants (``_prepared``) with the limits, kept by the object."""
        return _prepared(self.links, _NO_LIMITS if self.limits is None else self.limits)

    @cached_property
    def _without_limits(self):
        return _prepared(self.links, _NO_LIMITS)

    def can_take(self, pose: Sequence[float], hint: tuple[float, ...]) -> bool:
        """Whether a robot-frame ``pose`` has joints inside the limits (``has_solution``, with the
        solver's constants kept by the object: the simulator asks it of every Cartesian target)."""
        return _solve(pose, self._within_limits, hint, _FIRST)[0] is not None

    def joints_of(self, pose: Sequence[float], hint: tuple[float, ...]) -> tuple[float, ...]:
        """The joints a robot-frame ``pose`` is taken to have (``motion.ArmPose.joints``, and so
        every joints status frame of the simulator): ``inverse`` near ``hint`` inside the limits,
        else ignoring them, else ``hint`` itself for a pose out of reach.  The solver straight,
        without ``inverse``'s messages (nothing is raised: the simulator asks this ~13,000 times
        in a 20-minute virtual job)."""
        best = _solve(pose, self._within_limits, hint, _NEAREST)[0]
        if best is None:
            best = _solve(pose, self._without_limits, hint, _NEAREST)[0]
            if best is None:
                return hint
        return best


# --- reachability (lint) ----------------------------------------------------------------------


def box_problem(robot_xyz: Sequence[float], box) -> str | None:
    """Why a robot-frame point is outside the profile's workspace box or reach radius, or None."""
    x, y, z = robot_xyz
    (x_low, x_high), (y_low, y_high), (z_low, z_high) = box.x_mm, box.y_mm, box.z_mm
    if (x_low <= x <= x_high and y_low <= y <= y_high and z_low <= z <= z_high
            and math.sqrt(x * x + y * y + z * z) <= box.reach_mm):
        return None  # the common case, asked of every target: the tests below, without their messages
    for name, value, (low, high) in zip("XYZ", robot_xyz, (box.x_mm, box.y_mm, box.z_mm)):
        if not low <= value <= high:
            return f"robot {name} = {value:.1f} mm is outside the workspace {low:g}…{high:g} mm"
    distance = math.sqrt(sum(v * v for v in robot_xyz))
    if distance > box.reach_mm:
        return f"point is {distance:.1f} mm from the robot origin, beyond the reach radius {box.reach_mm:g} mm"
    return None


def reach_problem(pose: Sequence[float], profile, origin_mm: Sequence[float] = (0.0, 0.0, 0.0), near=None) -> str | None:
    """Why the arm cannot take a worktable ``pose`` (robot = worktable + origin), or None.

    Checks, in order: the profile's workspace box and reach radius (robot frame, around the
    robot origin), then an IK solution inside the joint limits.
    """
    x, y, z = (pose[k] + origin_mm[k] for k in range(3))
    problem = box_problem((x, y, z), profile.workspace)
    if problem is not None:
        return problem
    try:
        inverse((x, y, z, *pose[3:6]), profile.links, near if near is not None else profile.poses[0],
                profile.joint_limits_deg)
    except Unreachable as error:
        return str(error)
    return None


def reachable(pose: Sequence[float], profile, origin_mm: Sequence[float] = (0.0, 0.0, 0.0), near=None) -> bool:
    """True when ``reach_problem`` finds nothing wrong."""
    return reach_problem(pose, profile, origin_mm, near) is None
