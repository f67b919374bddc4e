"""Whether a position report on a move's path shows the arm ran that move, or may be the arm on
another pending frame (``Sightings.note_runs``, which counts the reports that prove a move ran
where no sign of a refusal could see one: ``Ledger.prove_ran``).

Strategy: a report lies on the paths of several pending frames at once: a line back over the
start of the next one, a later target on a refused move's path (tests/test_found8_*.py).  Under
a refusal of the move the arm runs every frame before it, then the frames after it from the
move's start — so a report that may be the arm on any of them proves nothing of the move.  Three
kinds of other frame leave it a proof: the same move again (a repeated job: the arm takes that
very move or refuses both), a frame that keeps the arm at the move's target or starts there, after
the move (the arm there needs a move to take it there: the move, or another frame the report lies
on, judged as well — for the first move after a refused one, only off the way it would take from
the refused move's start), and a straight move running against the move (the arm on it goes
backwards along the move's path: a report ahead of the one read just before it is not the arm
there, ``moved_ahead``).  Frames no stream can judge match nothing, as everywhere.  A flat cost:
the frames whose paths may meet a move's are found once per move as they are written
(``near_frames``), and a report is matched against those alone.
"""

from __future__ import annotations

from itertools import islice

from ..motion_paths import dot3, sub3
from .frames import SentFrame

CLEAR, AGAINST, ELSEWHERE = 0, 1, 2  # what a report on a move says of the other pending frames
# Two planned poses this close (mm, deg) are the same (``same_move``): the same numbers in a
# script, give or take the float arithmetic of relative moves.
SAME_POSE_TOLERANCE = 1e-6


class OthersOnPath:
    """Which other pending frames one report lies on (``match``), of those that may meet a move's
    path (``near_frames``).  ``off_way(move, after)``: whether the report is off the way the arm
    would take to ``after``'s target from ``move``'s start (``evidence.off_the_refused_way``)."""

    __slots__ = ("pending", "match", "off_way", "windows")

    def __init__(self, pending, match, off_way) -> None:
        self.pending, self.match, self.off_way = pending, match, off_way
        self.windows: dict[int, object] = {}  # frame index: the report's window on it (None: not on it)

    def lies_on(self, move: SentFrame) -> int:
        """CLEAR: on no other frame that leaves the arm elsewhere; AGAINST: only on moves running
        against ``move`` (then it proves a run only ahead of the report before it); else ELSEWHERE."""
        result, windows = CLEAR, self.windows
        for sent in near_frames(move, self.pending):
            found = windows[sent.index] if sent.index in windows else windows.setdefault(sent.index, self.match(sent))
            if found is None or same_move(sent.segment, move.segment) or (
                    sent.index > move.index and self.at_target_after(sent, found, move)):
                continue
            if not runs_against(sent.segment, move.segment):
                return ELSEWHERE
            result = AGAINST
        return result

    def at_target_after(self, sent: SentFrame, found, move: SentFrame) -> bool:
        """Whether the report on ``sent``, a frame after ``move``, is the arm at ``move``'s target:
        ``sent`` keeps it there, or it is at ``sent``'s start there, off the way ``sent`` would
        take from the start of ``move`` refused."""
        one, target, tolerance_mm = sent.segment, move.segment.end, move.xyz_tolerance_mm
        if one.start.origin_mm != target.origin_mm or not _within(one.start.xyz, target.xyz, tolerance_mm):
            return False
        return _within(one.start.xyz, one.end.xyz, 0.0) or found[0] <= 0.0 and self.off_way(move, sent)


def near_frames(move: SentFrame, pending) -> list[SentFrame]:
    """The pending frames but ``move`` whose path may meet ``move``'s within the two reports'
    tolerances (``_box``): the only ones a report on its path may lie on as well.  Kept on the
    move (``SentFrame.near``) and extended as frames are written, so a report searches a few
    frames, not a deep queue."""
    first = pending[0].index
    if move.near is None:
        move.near, move.near_through = [], first - 1
    last = pending[-1].index
    if move.near_through < last:
        segment = move.segment
        lo, hi = _box(segment, move.xyz_tolerance_mm)
        origin_mm = segment.start.origin_mm
        for sent in islice(pending, max(move.near_through + 1, first) - first, None):
            box = _box(sent.segment, sent.xyz_tolerance_mm, origin_mm)
            if sent is not move and (box is None or box[0][0] <= hi[0] and lo[0] <= box[1][0] and box[0][1] <= hi[1]
                                     and lo[1] <= box[1][1] and box[0][2] <= hi[2] and lo[2] <= box[1][2]):
                move.near.append(sent)
        move.near_through = last
    if move.near and move.near[0].index < first:
        move.near = [sent for sent in move.near if sent.index >= first]  # consumed
    return move.near


def _box(segment, tolerance_mm: float, origin_mm=None):
    """The corners of a straight or still frame's box, ``tolerance_mm`` around it; None where a
    path leaves it (an arc, a joint move) or the frame is in another worktable frame than
    ``origin_mm`` (given)."""
    if segment.kind not in ("line", "still") or segment.end.origin_mm != segment.start.origin_mm or (
            origin_mm is not None and segment.start.origin_mm != origin_mm):
        return None
    a, b = segment.start.xyz, segment.end.xyz
    return (tuple(min(a[i], b[i]) - tolerance_mm for i in range(3)),
            tuple(max(a[i], b[i]) + tolerance_mm for i in range(3)))


def same_move(one, other) -> bool:
    """Whether two segments are the same straight move: from the same pose to the same target."""
    return (one.kind == other.kind == "line" and one.start.origin_mm == other.start.origin_mm
            and _within(one.start.cartesian, other.start.cartesian, SAME_POSE_TOLERANCE)
            and _within(one.end.cartesian, other.end.cartesian, SAME_POSE_TOLERANCE))


def _within(one, other, tolerance: float) -> bool:
    return max(abs(a - b) for a, b in zip(one, other)) <= tolerance


def runs_against(one, other) -> bool:
    """Whether straight move ``one`` runs backwards along straight move ``other``'s direction."""
    if not (one.kind == other.kind == "line" and one.start.origin_mm == other.start.origin_mm):
        return False
    return dot3(sub3(one.end.xyz, one.start.xyz), sub3(other.end.xyz, other.start.xyz)) < 0.0


def run_seen(move: SentFrame, lo: float, report: int, others: OthersOnPath) -> int:
    """How many reports on ``move``'s path this one (number ``report``, the lower end ``lo`` of its
    window there) proves the arm ran ``move`` at: 1 past its start where it may be the arm nowhere
    else; where it may be the arm on a move running against ``move`` only, none until a report in
    a row shows the arm going forward along ``move`` (``moved_ahead``) — then both count."""
    last, move.last_on_path = move.last_on_path, (report, lo, False)
    if lo <= 0.0:
        return 0  # at its start: no run shown
    elsewhere = others.lies_on(move)
    if elsewhere == ELSEWHERE:
        return 0
    ahead = moved_ahead(last, report, lo, move.xyz_tolerance_mm / move.segment.length)
    if elsewhere == AGAINST and not ahead:
        move.last_on_path = (report, lo, True)  # counted once a report ahead of it comes
        return 0
    return 2 if ahead and last is not None and last[2] else 1  # this one, and the one before if it waited


def moved_ahead(last, report: int, lo: float, step: float) -> bool:
    """Whether the report read just before ``report`` lay on the move more than ``step`` (a
    reading's tolerance, a fraction of the move) behind this one (``last``: its number and the
    lower end of its window there; ``lo`` this one's): the arm went forward along it — not at rest
    (a reading within its jitter), nor backwards as on a move running against it (between two
    reports in a row it would have had to pass this point and come back)."""
    return last is not None and last[0] == report - 1 and lo - last[1] > step
