"""The closed-form IK as it was before the one flat solver (issue 13): a test-only reference.

``inverse``, ``solutions`` and their helpers copied verbatim from armctl/core/kinematics.py at
88a2591 (enumerating generators, the wrist matrix by ``_mul``), so that
tests/test_ik_flat.py can hold the package's flat solver to the same answers bit for bit.
Not part of the package: the IK math lives once, in armctl/core/kinematics.py."""

from __future__ import annotations

import math
from typing import Iterator, Sequence

from armctl.core.kinematics import JOINT_COUNT, Links, Unreachable, wrap_deg
from armctl.core.kinematics_frames import arm_rotation as _arm, rotation_product as _mul
from armctl.core.kinematics_inverse import _fit, flange_of as _flange_of


def solutions(pose: Sequence[float], links: Links, near: Sequence[float] | None = None) -> list[tuple[float, ...]]:
    """Every closed-form solution (deg, each angle in (−180, 180]) for a robot-frame pose.

    At a singularity the free angle is taken from ``near`` (J1 when the wrist centre is on the
    base axis, J4 when J5 = 0).  An empty list means the pose is out of reach.
    """
    return list(_solutions(pose, links, near))


def _solutions(pose, links, near) -> Iterator[tuple[float, ...]]:
    """``solutions``, one at a time, in the same order (so a caller may stop at the first that fits)."""
    near = near or (0.0,) * JOINT_COUNT
    near_j4 = math.radians(near[3])
    for j1, j2, t, flange in _arm_solutions(pose, links, near):
        for j4, j5, j6 in _wrist_of(j1, t, flange, near_j4):
            yield tuple(wrap_deg(math.degrees(a)) for a in (j1, j2, t - j2, j4, j5, j6))


def _arm_solutions(pose, links, near) -> Iterator[tuple[float, float, float, tuple]]:
    """(J1, J2, J2 + J3 in radians, the flange rotation) for each way the first three joints
    place the wrist centre of ``pose``: front/back, elbow up/down."""
    x, y, z, b0, b1, w = pose
    flange = _flange_of(b0, b1, w)
    d6 = links.tool_mm
    wx, wy, wz = x - d6 * flange[0], y - d6 * flange[3], z - d6 * flange[6]
    a2, a3, d4 = links.upper_arm_mm, links.elbow_offset_mm, links.forearm_mm
    reach = math.hypot(d4, a3)
    gamma = math.atan2(a3, d4)
    if math.hypot(wx, wy) < 1e-9:
        yaws = [math.radians(near[0])]
        yaws.append(yaws[0] + math.pi)
    else:
        yaws = [math.atan2(wy, wx)]
        yaws.append(yaws[0] + math.pi)
    for j1 in yaws:
        u = wx * math.cos(j1) + wy * math.sin(j1) - links.shoulder_offset_mm
        v = wz - links.base_height_mm
        cos_d = (u * u + v * v - a2 * a2 - reach * reach) / (2 * a2 * reach)
        if abs(cos_d) > 1 + 1e-9:
            continue
        cos_d = max(-1.0, min(1.0, cos_d))
        for delta in {math.acos(cos_d), -math.acos(cos_d)}:
            alpha = math.atan2(v, u) + math.atan2(reach * math.sin(delta), a2 + reach * math.cos(delta))
            j2 = math.pi / 2 - alpha
            yield j1, j2, gamma - (alpha - delta), flange


def _wrist_of(j1, t, flange, near_j4):
    """The wrist's (J4, J5, J6) radians for an arm at J1 = ``j1``, J2 + J3 = ``t``."""
    arm = _arm(j1, t)
    wrist = _mul((arm[0], arm[3], arm[6], arm[1], arm[4], arm[7], arm[2], arm[5], arm[8]), flange)
    return _wrist_solutions(wrist, near_j4)


def _wrist_solutions(m, near_j4):
    """(j4, j5, j6) with Rx(j4)·Ry(j5)·Rx(j6) = m: the two wrist flips, or one at J5 = 0/180."""
    j5 = math.acos(max(-1.0, min(1.0, m[0])))
    if math.sin(j5) < 1e-7:
        if m[0] > 0:  # J5 = 0: only J4 + J6 is fixed
            return [(near_j4, 0.0, math.atan2(m[7], m[4]) - near_j4)]
        return [(near_j4, math.pi, near_j4 - math.atan2(m[7], m[4]))]  # J5 = 180: J4 − J6 fixed
    j4, j6 = math.atan2(m[3], -m[6]), math.atan2(m[1], m[2])
    return [(j4, j5, j6), (j4 + math.pi, -j5, j6 + math.pi)]


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
    # The solutions of ``solutions``, in its order, fitted joint by joint as ``_fit`` fits them
    # and costed as the sum of squares in joint order; but the first three joints of an arm
    # placement are fitted once for both wrist flips, and a solution is dropped as soon as its
    # cost so far reaches the best's (every term is >= 0; ``worst`` only matters while there
    # is no best): the simulator asks this of every joints status frame, 40,000 in 20 minutes
    # (tests/test_kinematics.py holds it equal to the plain enumeration).
    lim = (None,) * JOINT_COUNT if limits is None else limits
    near_j4 = math.radians(near[3])
    best, best_cost, worst, reachable = None, math.inf, None, False
    for j1, j2, t, flange in _arm_solutions(pose, links, near):
        reachable = True
        arm_fitted, arm_cost = _fitted_cost((j1, j2, t - j2), near, lim, 0, 0, best_cost)
        if arm_fitted is None:
            if worst is None:
                worst = arm_cost
            continue
        for wrist in _wrist_of(j1, t, flange, near_j4):
            wrist_fitted, cost = _fitted_cost(wrist, near, lim, 3, arm_cost, best_cost)
            if wrist_fitted is None:
                if worst is None:
                    worst = cost
                continue
            best, best_cost = arm_fitted + wrist_fitted, cost
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


def _fitted_cost(angles_rad, near, limits, first: int, cost, bound):
    """(the angles in degrees as ``inverse`` fits them, ``cost`` + their squared distance to
    ``near``) for joints ``first``, ``first`` + 1, …; (None, (k, angle)) for the first that
    does not fit its limits; (None, None) as soon as the cost reaches ``bound``."""
    fitted = []
    for k, angle in enumerate(angles_rad, first):
        angle = wrap_deg(math.degrees(angle))
        value = _fit(angle, near[k], limits[k])
        if value is None:
            return None, (k, angle)
        cost += (value - near[k]) ** 2
        if not cost < bound:  # the very test inverse keeps a solution by
            return None, None
        fitted.append(value)
    return tuple(fitted), cost
