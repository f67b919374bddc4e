"""Forward and inverse kinematics of the 6-axis arm: closed form, spherical wrist (the façade).

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

Callers import every name from here; the parts, each importing only downwards:
armctl/core/kinematics_frames.py (the frames and conventions, the types, rotations, ``forward``),
armctl/core/kinematics_inverse.py (the solver, ``inverse``, ``has_solution``, ``Kinematics``) and
armctl/core/kinematics_regions.py (``ball_has_solution``, ``SolvableCells``, ``box_problem``).  This
module keeps the profile's reach checks, ``reach_problem`` and ``reachable``.
"""

from __future__ import annotations

from typing import Sequence

from .kinematics_frames import (  # noqa: F401 - the façade offers every part's names
    JOINT_COUNT, CartesianPose, Links, Unreachable, forward, rotation_matrix, wrap_deg,
)
from .kinematics_inverse import Kinematics, has_solution, inverse, solutions  # noqa: F401
from .kinematics_regions import SolvableCells, ball_has_solution, box_problem  # noqa: F401




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
