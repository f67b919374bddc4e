"""Position and joint evidence: which pending frames a status report may have been taken on.

Strategy: a report is matched against the paths of the pending frames (``search``), and the
result is a ``Sighting`` — the earliest frame the arm is at least at, every candidate with the
window of its path the report puts the arm in, and whether the previous report of the same
stream agrees.  This part concludes nothing itself: the streamer moves the lower bound only on
an agreed ``Sighting`` and the estimate on any.  What it guarantees is that the earliest frame
is sound:

* a stream stops at a frame it cannot judge: X/Y/Z at a frame whose X/Y/Z only the profile's
  unverified kinematics know (``xyz_unknown``) — counted on a move from such a frame's end, never
  past it — and joint halves at the first pending Cartesian frame (that would need IK), and on
  a joint move from a Cartesian end (its real path is not the planned one);
* the earliest candidate counts (a point on several pending paths proves only the first), and a
  match beyond an unsearched gap proves only the gap's first frame (``search``'s flat cost);
* a window on the last frame a stream can judge has no upper end when the report is at its end:
  the arm may be past it already.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass
from itertools import islice

from ..motion import distance_to_path
from .constants import (
    JOINT_TOLERANCE_DEG,
    JOINT_TRACE_FRACTION,
    JOINT_TRACE_SLACK,
    POSITION_TOLERANCE_MM,
    RUN_PROOF_MIN_S,
    SCAN_WINDOW_FRAMES,
)
from .frames import SentFrame, est_end
from .geometry import (
    TimeMemo, distance_to_chord_mm, estimate_off_s, in_frame, joint_half_fraction, start_unknown, trace_deviation_mm,
)
from .ledger import Ledger
from .run_proof import OthersOnPath, run_seen

RUN_SCAN_MOVES = 3  # the long moves not proven yet that one position report is matched against (``note_runs``)
# How many windows short of a path's end a report lies inside it (``count_inside``):
# 2 windows of a straight move are 4 tolerances (2 mm).
END_MARGIN = 2.0


@dataclass(slots=True)
class Sighting:
    """One report matched: ``earliest`` (None: on no pending path searched), its ``candidates``
    (index, lo, hi), ``settled`` when the estimate already has the arm where the earliest does;
    ``previous`` is this stream's last earliest (None: no agreement possible) and
    ``least_fraction`` the least fraction of ``earliest`` both reports allow (0 unless both were
    on it).  ``could_be_on(frame)`` says whether the report may lie on a frame (the loss
    checks); ``off_path_xyz`` is the position when it lies on no pending path (the reversal
    check); ``beyond``: only frames past one the stream cannot judge matched (``end`` on), so it
    may re-time the estimate, and nothing else."""

    stream: str
    earliest: int | None
    candidates: list
    settled: bool = False
    could_be_on: object = None
    previous: int | None = None
    least_fraction: float = 0.0
    match: object = None
    end: int = 0
    off_path_xyz: tuple | None = None
    beyond: bool = False


class Sightings:
    """Matches reports against the pending frames (see the module docstring)."""

    def __init__(self, ledger: Ledger, memo: TimeMemo, kinematics_verified: bool, reports_robot_xyz: bool,
                 unknown_start_mm: float) -> None:
        self.ledger, self.memo = ledger, memo
        self.unknown_start_mm = unknown_start_mm  # how far the profile's unverified kinematics may put a start (``start_error_mm``)
        self.kinematics_verified = kinematics_verified
        self.reports_robot_xyz = reports_robot_xyz
        self.last_candidate: dict[str, int | None] = {}
        self.last_fraction: dict[str, float | None] = {}  # the least fraction on that candidate
        self.cartesian: deque[int] = deque()  # indexes of pending Cartesian frames (joint halves stop there)
        self.blind: deque[int] = deque()  # indexes of pending frames whose X/Y/Z cannot be judged (positions stop there)
        self.joints_unknown: deque[int] = deque()  # ... joint frames whose path is not the planned one (joint halves stop past them)
        self.long_moves: deque[SentFrame] = deque()  # the straight moves a refusal of would show (``written``): long, or foreseen
        self.blind_through = -1  # the last frame written whose X/Y/Z no report can judge
        self.position_reports = 0  # the X/Y/Z reports read: which one came just before another (``note_runs``)

    def written(self, frame: SentFrame) -> None:
        """Note what a frame just written lets each stream judge."""
        segment = frame.segment
        verified = self.kinematics_verified
        if segment.kind == "joint" and verified:
            frame.xyz_tolerance_mm = POSITION_TOLERANCE_MM + JOINT_TRACE_SLACK * trace_deviation_mm(segment)
        if segment.kind in ("line", "arc"):
            self.cartesian.append(frame.index)
        elif not frame.path_known:
            self.joints_unknown.append(frame.index)
        frame.judged_by_start = segment.kind == "line" and segment.length > 4 * frame.xyz_tolerance_mm
        if frame.judged_by_start:
            # a short one refused shows nowhere (no gap, no standing: the arm runs on at once), so
            # only one whose refusal the plan foresees needs proof, wherever it stands
            foreseen = self.may_refuse(segment)
            frame.needs_run_proof = foreseen
            if foreseen or segment.duration_s >= RUN_PROOF_MIN_S:
                self.long_moves.append(frame)
        if not verified and (segment.kind == "joint" or segment.end.xyz_derived) or not frame.path_known:
            self.blind.append(frame.index)
            self.want_proof(frame)

    def want_proof(self, frame: SentFrame) -> None:
        """``frame``, whose X/Y/Z no report can judge, is written: the not-begun sign cannot see a
        refusal of it (if a straight move: its start only the profile's kinematics know), nor of a
        straight move still pending before it — a report at that one's start may lie on this one
        (``standing_at_start``), and refused, the arm runs this one at once from there, so neither
        a gap shows (no report judges how long it took) — so only the position reports on their
        paths prove the long ones ran (``note_runs``, ``Ledger.prove_ran``) — and a short one
        whose refusal the plan foresees wherever it stands (``may_refuse``)."""
        first = self.ledger.pending[0].index if self.ledger.pending else frame.index
        for sent in reversed(self.long_moves):
            if sent.index <= self.blind_through or sent.index < first:
                break
            sent.needs_run_proof = True
        self.blind_through = frame.index

    def note_runs(self, match, xyz) -> None:
        """One position report at ``xyz`` (``match``: where it lies on a frame's path) on the long
        moves still pending (``written``) and the frame after each (``count_inside``,
        ``off_the_refused_way``), whatever else it may lie on (a frame no stream can judge before
        them, an SD program): it proves only a run.  On a move's own path it counts only where it
        may not be the arm on another pending frame (``run_proof.run_seen``): the line before a
        refused move, running back over its start, and the target after it, on its path, each put
        two reports "on" it (tests/test_found8_*.py).
        For a flat cost, only the oldest ``RUN_SCAN_MOVES`` not proven yet: the arm runs them in
        order (a move missed costs only the weaker claim, never a false one)."""
        moves, pending = self.long_moves, self.ledger.pending
        first = pending[0].index if pending else self.ledger.sent
        while moves and (moves[0].index + 1 < first or moves[0].moved_seen >= 2):
            moves.popleft()  # proven, or it and the frame after it consumed: judged (``Ledger.prove_ran``)
        if not moves:
            return  # (nothing to scan: no closure or matcher built, once a report)
        robot = self.reports_robot_xyz

        def off_way(move: SentFrame, after: SentFrame) -> bool:
            return off_the_refused_way(move, after, in_frame(xyz, after.segment.start.origin_mm) if robot else xyz,
                                       self.start_error_mm(move))

        others = OthersOnPath(pending, match, off_way)
        scanned = 0
        for sent in moves:
            k = sent.index - first
            if sent.moved_seen >= 2 or 0 <= k + 1 < len(pending) and pending[k + 1].inside_seen >= 2:
                continue  # proven already
            if k >= 0:
                found = match(sent)
                if found is not None:
                    sent.moved_seen += run_seen(sent, found[0], self.position_reports, others)
            if k + 1 < len(pending) and pending[k + 1].path_known:
                after = pending[k + 1]
                found = match(after)
                if found is not None and count_inside(*found) and off_way(sent, after):
                    after.inside_seen += 1
            scanned += 1
            if scanned == RUN_SCAN_MOVES:
                break

    @staticmethod
    def may_refuse(segment) -> bool:
        """Whether the plan foresees the arm refusing ``segment``'s target: the profile's own
        kinematics find no joints for it inside the limits (lint's L103, a warning only with
        illustrative numbers; the simulator refuses such a target, armctl/sim/executor.py)."""
        end = segment.end
        return not end.kinematics.can_take(end.robot_cartesian, end.ik_hint)

    def start_error_mm(self, sent: SentFrame) -> float:
        """How far from its planned start ``sent`` may really begin: 0 where the plan knows it, the
        time bound's ``unknown_start_mm`` where only the profile's unverified kinematics put it (a
        joint move's or a POSE's end), without bound where an SD program left the arm."""
        if sent.path_known:
            return 0.0
        return self.unknown_start_mm if start_unknown(sent.segment, self.kinematics_verified) else math.inf

    def remember(self, stream: str, earliest: int | None, candidates) -> tuple[int | None, float]:
        """Keep this report's earliest frame for the next of its stream; the previous one's and
        the least fraction both allow on ``earliest`` (0 unless both were on it)."""
        previous = self.last_candidate.get(stream)
        previous_fraction = self.last_fraction.get(stream)
        self.last_candidate[stream] = earliest
        fraction = None
        for index, lo, _ in candidates:
            if index == earliest:
                fraction = lo
                break
        self.last_fraction[stream] = fraction
        both = previous == earliest and fraction is not None and previous_fraction is not None
        return previous, (max(0.0, min(previous_fraction, fraction)) if both else 0.0)

    def _sighting(self, stream: str, earliest, candidates, settled: bool, could_be_on, match, end: int,
                  off_path_xyz=None) -> Sighting:
        previous, least = self.remember(stream, earliest, candidates)
        return Sighting(stream, earliest, candidates, settled, could_be_on, previous, least, match, end, off_path_xyz)

    def position(self, xyz, now: float) -> Sighting | None:
        """A reported X/Y/Z at ``now``; None when it can say nothing."""
        robot, verified = self.reports_robot_xyz, self.kinematics_verified
        self.position_reports += 1

        def match(sent: SentFrame):
            segment = sent.segment
            if not verified and (segment.kind == "joint" or segment.end.xyz_derived):
                return None  # its X/Y/Z exist only through the profile's unverified FK
            distance, fraction = distance_to_path(segment, in_frame(xyz, segment.start.origin_mm) if robot else xyz)
            if distance > sent.xyz_tolerance_mm:
                return None
            if segment.kind == "joint":
                slack = JOINT_TRACE_FRACTION  # matched on chords of its trace
            else:
                slack = sent.xyz_tolerance_mm / segment.length if segment.length > 0 else 1.0
            if not sent.path_known:
                # on the planned path near where the real one may run: at least this far along,
                # perhaps past its end already (the search stops at it), so no upper end —
                # else the arm at rest at its target would hold the estimate there for ever
                return fraction - slack, math.inf
            return fraction - slack, fraction + slack

        if self.long_moves:
            self.note_runs(match, xyz)
        # A position says nothing about a frame whose X/Y/Z only the unverified kinematics know,
        # nor about any frame after it: the arm may be on that frame, at a point that also lies
        # on a later path (a wrist turning in place, then a move that starts there).
        pending = self.ledger.pending
        blind, first = self.blind, pending[0].index if pending else self.ledger.sent
        while blind and blind[0] < first:
            blind.popleft()  # consumed
        end = blind[0] - first if blind else len(pending)
        if blind and not pending[end].path_known:
            end += 1  # a line from an unverified joint end: a sighting may count on it, never past it
        if blind and end == 0:
            return None

        def could_be_on(sent: SentFrame) -> bool:  # for the loss check: a frame this report may lie on
            segment = sent.segment
            return (not verified and (segment.kind == "joint" or segment.end.xyz_derived) or not sent.path_known
                    or match(sent) is not None)

        earliest, candidates, settled = self.search(match, end, now)
        if earliest is None and end < len(pending):
            # the arm may be on the frame that cannot be judged: no evidence — but a report on
            # a later frame's path still tells the estimate where the arm most likely is
            return Sighting("position", None, candidates, match=match, end=end, beyond=True)
        off_path = xyz if earliest is None and not blind else None
        return self._sighting("position", earliest, candidates, settled, could_be_on, match, end, off_path)

    def joint_half(self, offset: int, values, now: float) -> Sighting | None:
        """Joints ``offset``…``offset+2`` reported at ``now``; None when they can say nothing.
        Joint halves say nothing about a Cartesian segment (that would need IK), so a match on a
        joint segment counts only up to the first pending Cartesian segment."""
        stream = f"joints{offset}"
        pending = self.ledger.pending
        if not pending:
            self.remember(stream, None, [])
            return None
        cartesian, first = self.cartesian, pending[0].index
        while cartesian and cartesian[0] < first:
            cartesian.popleft()  # consumed
        end = cartesian[0] - first if cartesian else len(pending)
        if end == 0:
            return None  # the arm may be on this Cartesian segment: no evidence from joints
        unknown = self.joints_unknown
        while unknown and unknown[0] < first:
            unknown.popleft()  # consumed
        if unknown and unknown[0] - first < end:
            # A joint move from a Cartesian end (its real start only the arm's IK knows): its
            # real path may pass along a later frame's, so a sighting counts on it, never past it.
            end = unknown[0] - first + 1
        verified = self.kinematics_verified

        def match(sent: SentFrame):
            if not verified and sent.segment.end.joints_derived:
                return None  # a still frame whose joints exist only through the profile's unverified IK
            found = joint_half_fraction(sent.segment, offset, values)
            if found is None or sent.path_known:
                return found
            return found[0], math.inf  # at least this far along, perhaps past its end already

        def could_be_on(sent: SentFrame) -> bool:  # for the loss check: joints cannot judge a Cartesian frame
            return sent.segment.kind not in ("joint", "still") or match(sent) is not None

        earliest, candidates, settled = self.search(match, end, now)
        if earliest is None and end < len(pending):
            return None  # the arm may be on the Cartesian segment after these: no evidence
        return self._sighting(stream, earliest, candidates, settled, could_be_on, match, end)

    def scan(self, match, end: int, now: float):
        """``search``'s (earliest, candidates)."""
        return self.search(match, end, now)[:2]

    def search(self, match, end: int, now: float):
        """Match one observation against the pending frames before ``end``: (earliest, candidates,
        settled) — settled when the earliest candidate is the one where the estimate has the arm
        (nothing to re-anchor).

        Flat cost: the search covers the oldest ``SCAN_WINDOW_FRAMES`` pending frames (where the
        lower bound's evidence is) and as many around the frame the estimate has in progress
        (where the re-anchoring evidence is); the rest only when neither window matches.  The
        earliest candidate stays sound: with no match among the oldest frames and a match
        further on, the arm is at least at the first frame not searched, so that is the
        earliest index reported (evidence no stronger than what was searched)."""
        pending = self.ledger.pending
        if 0 < end < len(pending):
            # Cut before a frame this stream cannot judge: seen at the end of the last frame it
            # can (or anywhere on a still one), the arm may be past it already, so that window has
            # no upper end — else an arm at rest there (a held G300 whose joints 4-6 the arc
            # keeps, the target of a joint move) would hold the estimate, and the job's end, back.
            edge, judge = pending[end - 1], match

            def match(sent: SentFrame):
                found = judge(sent)
                if sent is edge and found is not None and found[1] >= 1.0:
                    return found[0], math.inf
                return found
        candidates: list[tuple[int, float, float]] = []
        time_at = self.memo.time_at
        head = min(end, SCAN_WINDOW_FRAMES)
        for k in range(head):
            sent = pending[k]
            found = match(sent)
            if found is not None:
                candidates.append((sent.index, *found))
                if estimate_off_s(sent, *found, now, time_at) == 0.0:
                    # The usual case: the earliest candidate is where the estimate has the arm,
                    # so no later candidate can change the bound or the estimate.
                    return sent.index, candidates, True
                break
        else:
            k = head

        def search(lo: int, hi: int) -> None:
            for j in range(lo, hi):
                sent = pending[j]
                found = match(sent)
                if found is not None:
                    candidates.append((sent.index, *found))

        search(k + 1, head)
        if head == end:
            return (candidates[0][0] if candidates else None), candidates, False
        in_head = bool(candidates)
        centre = bisect_right(pending, now, key=est_end)  # the frame the estimate has in progress
        lo = max(head, centre - SCAN_WINDOW_FRAMES // 2)
        hi = min(end, max(lo, centre + SCAN_WINDOW_FRAMES // 2))
        search(lo, hi)
        if in_head or (candidates and lo == head):
            return candidates[0][0], candidates, False
        if candidates:
            # Nothing among the oldest frames: the arm is at least at the first frame not searched.
            return pending[head].index, candidates, False
        search(head, lo)  # neither window matched (the estimate is far off, or this is noise)
        search(hi, end)
        return (candidates[0][0] if candidates else None), candidates, False


def standing_at_start(found: Sighting | None, pending) -> int | None:
    """The head frame when this position report puts the arm at its start and on no later frame:
    the arm has not begun it, so time must not count it done (``TimeBound.standing_at``, through
    ``Losses.check_not_begun``, which wants two such reports after its deadline, and lets go of
    it only when two in a row agree on the arm elsewhere: a corrupted report, alone, never does).
    An arm that runs its frames at most ``slowest_factor`` times slower has left the start of a
    move by its deadline; one still there refused it (a target out of its reach: the simulator
    refuses those, armctl/sim/executor.py), lost it, or is slower than the time bound allows — and
    a move counted done by time there let the job end "finished" at its last target
    (tests/test_sim_reach.py).  Only a straight move whose path is the planned one and longer than
    the report's tolerance can tell (its start is not its end), and none a RESET CONNECTOR may have
    cleared (reports decide those, as ``TimeBound.advance`` leaves them); the later frames are
    searched only then."""
    if found is None or found.earliest is None or not pending:
        return None
    head = pending[0]
    segment = head.segment
    if found.earliest != head.index or not head.judged_by_start or not head.path_known or head.may_be_cleared:
        return None
    window = next((candidate for candidate in found.candidates if candidate[0] == head.index), None)
    if window is None or window[1] > 0.0 or window[2] >= 1.0:
        return None
    if any(found.could_be_on(later) for later in islice(pending, 1, None)):
        return None  # a later frame passes through the start: the arm may have run on to it
    return head.index


def count_inside(lo: float, hi: float) -> bool:
    """Whether a report between fractions ``lo`` and ``hi`` of a frame's path lies inside it, away
    from its end (the window ends ``END_MARGIN`` windows short of it): the arm began that frame
    where the plan has it begin — at the target of the frame before, which a refused target leaves
    unreached (a path from elsewhere to the same end meets this one only near the end)."""
    return lo > 0.0 and hi + END_MARGIN * (hi - lo) < 1.0


def off_the_refused_way(before: SentFrame, after: SentFrame, xyz, start_error_mm: float) -> bool:
    """Whether a report at ``xyz`` (in ``after``'s frame), inside the path of ``after``, shows the
    arm began it where ``before`` ends: it lies off every way the arm could take to the same target
    were ``before`` refused — a straight line from where ``before`` really begins, up to
    ``start_error_mm`` from its planned start — by more than the report's tolerance (a line back
    through that start, or from near it to a short move's target, runs inside the next path too).
    Only a straight ``after`` can tell (an arc from elsewhere is another arc)."""
    if after.segment.kind != "line" or math.isinf(start_error_mm):
        return False
    return (distance_to_chord_mm(xyz, before.segment.start.xyz, after.segment.end.xyz)
            > start_error_mm + after.xyz_tolerance_mm)


def ran_at_rest(last: SentFrame, recent_sent, kinematics_verified: bool) -> bool:
    """Whether the arm at rest at the target of ``last`` (a frame written; the caller saw it
    there) proves it ran — had it been dropped or cleared, the arm would rest where an
    earlier frame ended — that is, unless that is where the arm may rest anyway: at its
    start, or at the end of an earlier frame kept (a way back to the same point), or
    somewhere only the profile's kinematics know (its path not the planned one)."""
    segment = last.segment
    if not (segment.moves_reported and last.path_known):
        return False
    by_joints = segment.kind == "joint" or segment.end.xyz_derived  # as job_arrival's at_end_of compares
    tolerance = 2 * (JOINT_TOLERANCE_DEG if by_joints else POSITION_TOLERANCE_MM)
    target = segment.end.joints if by_joints else segment.end.xyz
    for sent in recent_sent:  # (``last`` among them: its own start, then no further)
        pose = segment.start if sent is last else sent.segment.end
        if pose.origin_mm != segment.end.origin_mm:
            return False
        derived = pose.joints_derived if by_joints else pose.xyz_derived  # the profile's IK/FK: where?
        if derived and not kinematics_verified:
            return False
        if max(abs(a - b) for a, b in zip(pose.joints if by_joints else pose.xyz, target)) <= tolerance:
            return False
        if sent is last:
            return True
    return False
