"""The frames written and not yet known consumed, and what proved each one consumed.

Strategy: the one record every part of the streamer reads.  ``pending`` holds the frames
written and not known finished, oldest first; ``consumed_lower_bound`` counts the rest.  Only
this module pops a frame, and each pop counts what proved it: the arm's reports (a sighting on
a later frame's path, the arm at rest at the last target), time alone, or a report that proves
the frame left the FIFO but not that it ran (``confirmed_unseen``).  The parts decide *when*;
the ledger keeps the count honest.
"""

from __future__ import annotations

from collections import deque

from ..protocol import Command, ResetConnector
from .constants import RECENT_SENT_FRAMES
from .frames import Evidence, SentFrame

RUNS_UNPROVEN_KEPT = 3  # the moves ``Ledger.runs_unproven`` keeps to name (``runs_unproven_count`` counts them all)


class Ledger:
    """The queue of frames written (see the module docstring)."""

    def __init__(self, control_on_arrival: bool) -> None:
        self.control_on_arrival = control_on_arrival
        self.pending: deque[SentFrame] = deque()  # frames not yet known consumed, oldest first
        self.sent = 0
        self.consumed_lower_bound = 0
        self.bound_evidence: Evidence | None = None  # what last advanced consumed_lower_bound
        self.last_done_tag = None
        # What proves each frame consumed (the summary's honesty): the arm's reports (a position
        # or joints on a later frame's path, the arm at rest at the last target) or time alone.
        self.confirmed_by_reports = 0
        self.confirmed_unseen = 0  # gone from the FIFO by a report, not proven run (``consume_one``)
        self.confirmed_by_time = 0
        self.first_time_only_index: int | None = None  # the first frame confirmed by time alone
        # Whether a frame gone from the FIFO has run: true when the connector holds every frame the
        # capacity rule lets in (the caller knows: a probed FIFO size, armctl/core/job.py's fifo_proven);
        # else a frame a full FIFO dropped leaves it as well.
        self.fifo_holds_all = True
        self.motion_sent_s = 0.0  # the model's motion time of every frame written
        self.sure_motion_sent_s = 0.0  # ... less the frames that may be any shorter (``SentFrame.sure_before_s``)
        self.recent_sent: deque[SentFrame] = deque(maxlen=RECENT_SENT_FRAMES)  # kept for the loss checks
        self.reset_index: int | None = None  # the last RESET CONNECTOR written (``record``)
        # A target the arm refused leaves it at the start of its move, which the not-begun sign sees
        # only on a straight move whose path is the planned one with no frame queued behind it whose
        # X/Y/Z no report can judge (``evidence.standing_at_start``): the others consumed with no
        # report to prove they ran (``prove_ran``)
        self.runs_unproven: list[SentFrame] = []
        self.runs_unproven_count = 0
        self.awaiting: SentFrame | None = None  # such a move, until the frame after it is consumed

    @property
    def frames_in_flight_bound(self) -> int:
        """Frames written and not known consumed: an upper bound of the FIFO's occupancy."""
        return self.sent - self.consumed_lower_bound

    def record(self, frame: SentFrame, command: Command) -> None:
        """Keep a frame just written (``frame.index`` is ``sent``)."""
        self.motion_sent_s += frame.segment.duration_s
        self.sure_motion_sent_s += frame.sure_s
        pending = self.pending
        if isinstance(command, ResetConnector):  # it clears what is queued when it acts
            self.reset_index = frame.index
            if self.control_on_arrival:
                for sent in pending:
                    sent.may_be_cleared = True
        elif (not self.control_on_arrival and self.reset_index is not None and pending
              and pending[0].index <= self.reset_index):
            frame.may_be_cleared = True  # queued behind a RESET CONNECTOR (H5) that may not have acted yet
        self.recent_sent.append(frame)
        pending.append(frame)
        self.sent += 1

    def cleared(self) -> None:
        """The connector may have discarded every frame still queued."""
        for sent in self.pending:
            sent.may_be_cleared = True

    def consume_one(self, by_reports: bool, at_rest: bool = False) -> None:
        """Count the oldest pending frame consumed: by the arm's reports, or by time — the time
        bound's, or (``at_rest``) the caller's, the trailing frames' at the end of a job (which
        leaves the time bound's own record, ``first_time_only_index``, as it was)."""
        sent = self.pending.popleft()
        self.last_done_tag = sent.tag
        self.prove_ran(sent)
        self.consumed_lower_bound += 1
        if by_reports:
            # A report on a later frame (or the arm at rest at the end) proves a frame left the
            # FIFO; that the arm ran it only if the FIFO held it (no drop, no RESET CONNECTOR),
            # or the arm at rest at its very target says so.
            if sent.seen or self.fifo_holds_all and not sent.may_be_cleared:
                self.confirmed_by_reports += 1
            else:
                self.confirmed_unseen += 1
        elif at_rest:
            self.confirmed_by_time += 1
            sent.by_time = True
        else:
            if self.confirmed_by_time == 0:
                self.first_time_only_index = self.consumed_lower_bound - 1
            self.confirmed_by_time += 1
            sent.by_time = True

    def prove_ran(self, sent: SentFrame) -> None:
        """``sent`` is consumed: a straight move whose refusal the not-begun sign cannot see (its
        start only the profile's kinematics know, or a frame whose X/Y/Z no report can judge queued
        behind it: ``Sightings.want_proof``) needs the arm's reports to prove it ran
        (``needs_run_proof``; and a short one anywhere whose refusal the plan foresees,
        ``Sightings.may_refuse``) — two on its path past its start, or two inside the next line's
        path off the way the arm would take to its target from this one's start, so where the plan
        has that one begin: at this one's target (``Sightings.note_runs``) — else it is counted in
        ``runs_unproven``: FINISHED would claim more than the reports prove."""
        awaiting, self.awaiting = self.awaiting, None
        if awaiting is not None and not (sent.index == awaiting.index + 1 and sent.path_known and sent.inside_seen >= 2):
            self.runs_unproven_count += 1
            if len(self.runs_unproven) < RUNS_UNPROVEN_KEPT:
                self.runs_unproven.append(awaiting)
        if sent.needs_run_proof and not (sent.moved_seen >= 2 or sent.seen):
            self.awaiting = sent

    def proven_run(self, sent: SentFrame) -> None:
        """The arm at rest at the very target of ``sent`` proves it ran: seen, so counted by the
        arm's reports when it is consumed — or counted again if time counted it consumed first
        (the time bound is often first on a job's last move: a sighting late in the move lets it
        confirm the frame before the arm has been still long enough to prove its rest).  The
        first frame confirmed by time alone is forgotten only once no such frame is left."""
        sent.seen = True
        if not sent.by_time:
            return
        sent.by_time = False
        self.confirmed_by_time -= 1
        self.confirmed_by_reports += 1
        if self.confirmed_by_time == 0:
            self.first_time_only_index = None

    def consume_before(self, index: int) -> None:
        """Every frame before ``index`` is known finished — except the rest of its group (a G300
        finishes with its G301, so evidence of the arc proves nothing about the G300)."""
        pending = self.pending
        if pending:
            k = index - pending[0].index
            if 0 < k < len(pending):
                index = pending[k].group_index
        while pending and pending[0].index < index:
            self.consume_one(by_reports=True)

    def tag_of(self, index: int):
        """The tag of frame ``index`` if it is among the frames kept, else None."""
        recent = self.recent_sent
        if not recent or not recent[0].index <= index <= recent[-1].index:
            return None
        return recent[index - recent[0].index].tag
