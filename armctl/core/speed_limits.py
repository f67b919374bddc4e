"""The most a frame may carry in its speed fields under a profile: one fact, two readers.

Strategy: lint's L201 refuses a script line whose F (or Q) passes it, and the feed override
(armctl/core/feed.py) clamps a rescaled speed to it, so both ask this one function.  Pure: the
profile's ``Speeds`` and a command type in, a number out (imports the protocol only, so the job
engine that applies the override stays free of lint's own imports).
"""

from __future__ import annotations

from .protocol import AccelLinearMove, ArcEnd, ArcStart, JointMove, LinearMove

CARTESIAN_MOVES = (LinearMove, AccelLinearMove, ArcStart, ArcEnd)  # speeds in mm/min


def speed_limit(command_type, speed) -> float | None:
    """The most a frame of ``command_type`` may carry in its speed fields (F, and Q of a G230)
    under the profile's ``speed`` (``Speeds``); None for a frame without a speed."""
    if command_type is JointMove:
        return speed.max_joint_deg_s
    return speed.max_linear_mm_min if command_type in CARTESIAN_MOVES else None
