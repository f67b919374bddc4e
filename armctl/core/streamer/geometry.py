"""Where on a frame's path, and when in its segment: the geometry the streamer's evidence reads.

Strategy: pure functions of a segment and an observation, plus one memo (``TimeMemo``) of the
times along the segment last asked about, shared by the parts so a sighting pays for each
``Segment.time_at_fraction`` once.  What the profile's kinematics may not be trusted with
(``xyz_unknown``, ``start_unknown``) is decided here, once, for every part.
"""

from __future__ import annotations

import math

from ..motion import Segment, distance_to_path
from .constants import JOINT_TOLERANCE_DEG
from .frames import SentFrame


def xyz_unknown(segment: Segment, verified: bool) -> bool:
    """Whether the segment's X/Y/Z exist only through the profile's unverified kinematics (a
    joint move, or a still frame whose pose was derived): no sighting can judge it."""
    return not verified and (segment.kind == "joint" or segment.end.xyz_derived)


def start_unknown(segment: Segment, verified: bool) -> bool:
    """Whether a segment starts where only the profile's unverified kinematics say — a
    Cartesian one at a joint move's end, a joint one at a Cartesian move's end: its real path
    is not the planned one."""
    if verified:
        return False
    if segment.kind == "joint":
        return segment.start.joints_derived
    return segment.kind in ("line", "arc") and segment.start.xyz_derived


def in_frame(xyz, origin_mm) -> tuple[float, float, float]:
    """Robot X/Y/Z in the worktable frame whose origin (in robot coordinates) is ``origin_mm``."""
    return (xyz[0] - origin_mm[0], xyz[1] - origin_mm[1], xyz[2] - origin_mm[2])


def distance_to_chord_mm(p, a, b) -> float:
    """The distance of point ``p`` from the straight segment ``a``-``b`` (X/Y/Z, mm)."""
    d = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    w = (p[0] - a[0], p[1] - a[1], p[2] - a[2])
    span = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    u = min(max((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / span, 0.0), 1.0) if span > 0.0 else 0.0
    return math.dist(p, (a[0] + d[0] * u, a[1] + d[1] * u, a[2] + d[2] * u))


def estimate_off_s(sent: SentFrame, lo: float, hi: float, now: float, time_at=None) -> float:
    """How far (s) the estimate is from having the arm between fractions ``lo`` and ``hi`` of
    ``sent``'s path at ``now`` (0 when it agrees); ``time_at`` as ``time_window``'s."""
    t_lo, t_hi = time_window(sent.segment, lo, hi, time_at)
    start = sent.est_end_s - sent.segment.duration_s
    return max(start + t_lo - now, now - (start + t_hi), 0.0)


def time_window(segment: Segment, lo: float, hi: float, time_at=None) -> tuple[float, float]:
    """Seconds after the segment began between which the arm is at fractions ``lo``…``hi``
    of its path (a path of zero length: the whole segment); ``time_at(segment, fraction)``:
    ``Segment.time_at_fraction`` (``TimeMemo.time_at`` remembers it)."""
    if hi == math.inf:  # no upper end: the arm may be past the frame (``Sightings``)
        return time_window(segment, lo, 0.0, time_at)[0], math.inf
    if segment.length <= 0:
        return 0.0, segment.duration_s
    if time_at is None:
        t_lo = 0.0 if lo <= 0.0 else segment.time_at_fraction(min(lo, 1.0))
        t_hi = segment.duration_s if hi >= 1.0 else segment.time_at_fraction(max(hi, 0.0))
        return t_lo, t_hi
    t_lo = 0.0 if lo <= 0.0 else time_at(segment, min(lo, 1.0))
    t_hi = segment.duration_s if hi >= 1.0 else time_at(segment, max(hi, 0.0))
    return t_lo, t_hi


class TimeMemo:
    """``Segment.time_at_fraction`` remembered for the segment last asked about."""

    def __init__(self) -> None:
        self.segment: Segment | None = None
        self.times: dict[float, float] = {}

    def time_at(self, segment: Segment, fraction: float) -> float:
        """``segment.time_at_fraction(fraction)``, remembered for the segment last asked about:
        one sighting asks for its window's ends up to four times each (the scan, the
        re-anchoring, the slowness check, the time bound's restart — from the previous
        sighting's least fraction, too), 4,461 sightings in a 20-minute job."""
        if segment is not self.segment:
            self.segment, self.times = segment, {}
        times = self.times
        t_s = times.get(fraction)
        if t_s is None:
            if len(times) >= 32:
                times.clear()
            t_s = times[fraction] = segment.time_at_fraction(fraction)
        return t_s


def joint_half_fraction(segment: Segment, offset: int, values) -> tuple[float, float] | None:
    """The fractions ``(lo, hi)`` along a joint or still segment between which joints
    offset…offset+2 equal ``values`` within tolerance; None if never (or if the segment is
    Cartesian).  A segment that does not move these joints matches along all its length."""
    if segment.kind not in ("joint", "still"):
        return None
    q0 = segment.start.joints[offset : offset + 3]
    q1 = segment.end.joints[offset : offset + 3]
    dq = [b - a for a, b in zip(q0, q1)]
    span = sum(d * d for d in dq)
    if span <= 1e-12:
        u, slack = 0.0, 1.0
    else:
        u = sum((v - a) * d for v, a, d in zip(values, q0, dq)) / span
        u = min(max(u, 0.0), 1.0)
        slack = JOINT_TOLERANCE_DEG / math.sqrt(span)
    if max(abs(v - (a + d * u)) for v, a, d in zip(values, q0, dq)) > JOINT_TOLERANCE_DEG:
        return None
    return (u - slack, u + slack) if slack < 1.0 else (0.0, 1.0)


def trace_deviation_mm(segment: Segment, chords: int = 16) -> float:
    """Largest distance between a joint segment's true X/Y/Z trace, sampled at the midpoints of
    ``chords`` equal steps in joint space, and the chords ``distance_to_path`` matches against."""
    worst = 0.0
    for k in range(chords):
        pose = segment.sample(segment.time_at_fraction((k + 0.5) / chords))
        worst = max(worst, distance_to_path(segment, pose.xyz)[0])
    return worst
