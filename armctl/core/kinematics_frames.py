"""The arm's kinematic conventions, its types and its forward kinematics: the bottom of armctl/core/kinematics.py's parts.

Strategy: everything the inverse solver (armctl/core/kinematics_inverse.py) and the region proofs
(armctl/core/kinematics_regions.py) share, defined once below them: ``Links``, ``CartesianPose``,
``Unreachable``, the rotations as row-major 9-tuples and ``forward``.  armctl/core/kinematics.py is
the façade that offers every name.  Pure functions of plain floats and tuples; no I/O.

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
from typing import NamedTuple, Sequence

from ..errors import ArmctlError

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


def rotation_product(a, b):
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (
        a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
        a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
        a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8,
    )


def rpy_matrix(b0, b1, w):
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


def arm_rotation(j1, t):
    """Rz(j1)·Ry(t): the forearm frame (t = J2 + J3)."""
    c1, s1, ct, st = math.cos(j1), math.sin(j1), math.cos(t), math.sin(t)
    return (c1 * ct, -s1, c1 * st, s1 * ct, c1, s1 * st, -st, 0.0, ct)


def tool_from_flange(r):
    """Tool frame = flange frame · F, F = Ry(−90)·Rx(180): tool x = flange z, y = −y, z = flange x."""
    return (r[2], -r[1], r[0], r[5], -r[4], r[3], r[8], -r[7], r[6])


flange_from_tool = tool_from_flange  # F is its own inverse


def rotation_matrix(b0_deg: float, b1_deg: float, w_deg: float) -> tuple[float, ...]:
    """The attitude as a row-major 3×3 rotation matrix (for comparing attitudes robustly)."""
    return rpy_matrix(math.radians(b0_deg), math.radians(b1_deg), math.radians(w_deg))


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
    flange = rotation_product(arm_rotation(j1, t), _xyx(j4, j5, j6))
    d6 = links.tool_mm
    x = radial * math.cos(j1) + d6 * flange[0]
    y = radial * math.sin(j1) + d6 * flange[3]
    z = z + d6 * flange[6]
    b0, b1, w = _rpy_of(tool_from_flange(flange))
    return CartesianPose(x, y, z, wrap_deg(math.degrees(b0)), wrap_deg(math.degrees(b1)), wrap_deg(math.degrees(w)))
