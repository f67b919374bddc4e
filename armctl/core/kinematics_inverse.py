"""Inverse kinematics: every closed-form solution of a pose, the one nearest a hint, or whether one fits.

Strategy: one solver, ``_solve``, written out flat (no generators, no matrix tuples):
``solutions``, ``inverse`` (the simulator asks it of every joints status frame, issue 11) and
``has_solution`` (lint asks it of every target, issue 13) are three ways of walking its
solutions, so the IK math exists once.  It enumerates the up to eight closed-form solutions
(front/back, elbow up/down, wrist flip), moves each angle by whole turns towards the hint,
drops those outside the joint limits and keeps the one nearest the hint.  ``Kinematics``
bundles links, limits and a home pose for repeated use.  The conventions are
armctl/core/kinematics_frames.py's; armctl/core/kinematics.py is the façade.  No I/O, stdlib only.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Sequence

from .kinematics_frames import (
    JOINT_COUNT, CartesianPose, Links, Unreachable, flange_from_tool, forward, rpy_matrix, wrap_deg,
)

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
def flange_of(b0_deg: float, b1_deg: float, w_deg: float):
    """The flange rotation for a tool attitude: scripts keep one attitude for many moves."""
    return flange_from_tool(rpy_matrix(math.radians(b0_deg), math.radians(b1_deg), math.radians(w_deg)))


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
    for bit: each wrist matrix entry is the sum ``rotation_product(arm^T, flange)`` forms, with arm =
    ``arm_rotation(j1, t)`` (tests/test_ik_flat.py holds all three modes to the enumeration,
    tests/ik_reference.py)."""
    x, y, z, b0, b1, w = pose
    f0, f1, f2, f3, f4, f5, f6, f7, f8 = flange_of(b0, b1, w)
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

    @cached_property
    def _answers(self) -> dict:
        """``can_take`` and ``joints_of`` answers already found, by the exact bits of the pose and
        the hint (``_answer_key``): both are pure functions of them and of this object, and a job
        asks them of the same few poses again and again (a 24,000-frame run of two alternating
        targets: 24,001 ``can_take`` of 6 distinct questions, 15,940 ``joints_of`` of 229).  At
        most ``_ANSWERS_MAX``, then it starts again: memory stays flat."""
        return {}

    def can_take(self, pose: Sequence[float], hint: tuple[float, ...]) -> bool:
        """Whether a robot-frame ``pose`` has joints inside the limits (``has_solution``, with the
        solver's constants kept by the object: the simulator asks it of every Cartesian target)."""
        key = _answer_key(True, pose, hint)
        answers = self._answers
        found = answers.get(key)
        if found is None:
            found = _solve(pose, self._within_limits, hint, _FIRST)[0] is not None
            _keep(answers, key, found)
        return found

    def joints_of(self, pose: Sequence[float], hint: tuple[float, ...]) -> tuple[float, ...]:
        """The joints a robot-frame ``pose`` is taken to have (``motion.ArmPose.joints``, and so
        every joints status frame of the simulator): ``inverse`` near ``hint`` inside the limits,
        else ignoring them, else ``hint`` itself for a pose out of reach.  The solver straight,
        without ``inverse``'s messages (nothing is raised: the simulator asks this ~13,000 times
        in a 20-minute virtual job); an answer found before is given again (``_answers``)."""
        key = _answer_key(False, pose, hint)
        answers = self._answers
        best = answers.get(key)
        if best is None:
            best = _solve(pose, self._within_limits, hint, _NEAREST)[0]
            if best is None:
                best = _solve(pose, self._without_limits, hint, _NEAREST)[0]
                if best is None:
                    best = _THE_HINT
            _keep(answers, key, best)
        return hint if best is _THE_HINT else best  # out of reach: the caller's very hint object


_ANSWERS_MAX = 4096
_THE_HINT = object()  # joints_of's answer for a pose out of reach, kept: "the hint you gave"
_ANSWER_BITS = struct.Struct("<?12d")  # which question, then the pose's and the hint's exact bits


def _answer_key(can_take: bool, pose, hint) -> bytes | None:
    """The question's exact bits: 0.0 and -0.0 (equal, and equal keys in a tuple) may have
    different answers (atan2), so a tuple of the floats would not do; None (not kept) for
    anything but six and six numbers."""
    try:
        return _ANSWER_BITS.pack(can_take, *pose, *hint)
    except (struct.error, TypeError, OverflowError):
        return None


def _keep(answers: dict, key: bytes | None, answer) -> None:
    if key is not None:
        if len(answers) >= _ANSWERS_MAX:
            answers.clear()
        answers[key] = answer
