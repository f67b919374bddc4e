"""Reachability of whole regions at once (lint): a ball of targets proven solvable, cells of proofs, the workspace box.

Strategy: lint asks "is there a solution?" of every target; ``ball_has_solution`` proves a whole
ball of targets at once (interval bounds on each joint of one branch of the closed form), and
``SolvableCells`` keeps such proofs per grid cube, sending only the targets of unproven cubes
to ``has_solution``: sound shortcuts, never approximations.  ``box_problem`` is the profile's
workspace box and reach radius.  Built on armctl/core/kinematics_frames.py and
armctl/core/kinematics_inverse.py; armctl/core/kinematics.py is the façade.  No I/O, stdlib only.
"""

from __future__ import annotations

import math
from typing import Sequence

from .kinematics_frames import Links, rotation_product, wrap_deg
from .kinematics_inverse import flange_of, has_solution

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
    f = flange_of(b0, b1, w)
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
            m = rotation_product(arm_t, f)
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
