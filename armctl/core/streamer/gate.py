"""The write gate: when may the next frame go to an arm that never acknowledges?

Strategy: rules over the other parts' numbers, no evidence of its own.  A frame may be written
once the previous one has left the wire (or ``write_ahead_s`` before, on a wall clock) and
while (a) the frames written less the lower bound stay under the FIFO's capacity less the
margin, (b) the estimated motion waiting behind the frame in progress, the new one included,
is at most the lead in the arm's seconds (a frame is always allowed once no more than
``FEED_AHEAD_S`` or the lead is queued in all), and (c) with control frames acting on arrival,
a control frame waits until the lower bound says every frame before it finished.  Why it
answered as it did is left in ``write_reason``.  The gate also plans the frame it is asked
about (``plan``), so the frame written is the frame judged.
"""

from __future__ import annotations

from ..motion import ArmPose, MotionModel, Planner, Segment
from ..protocol import CONTROL_COMMANDS, ArcStart, Command
from .constants import FEED_AHEAD_S
from .estimate import Estimate
from .frames import WaitReason
from .geometry import in_frame
from .ledger import Ledger


class Gate:
    """The write rules (see the module docstring)."""

    def __init__(self, ledger: Ledger, estimate: Estimate, model: MotionModel, start: ArmPose, *, lead_s: float,
                 limit_frames: int, frame_s: float, now: float, write_ahead_s: float) -> None:
        if lead_s <= 0:
            raise ValueError("lead_s must be greater than 0")
        self.ledger, self.estimate = ledger, estimate
        self.planner = Planner(model, start)
        connector = model.profile.connector
        self.control_on_arrival = connector.control_on_arrival
        self.reports_robot_xyz = connector.reports_robot_xyz
        self.lead_s = lead_s
        self.limit_frames = limit_frames
        self.frame_s = frame_s
        self.wire_free_s = now
        self.write_ahead_s = write_ahead_s
        self.peeked: tuple[Command, Segment] | None = None
        self.write_reason = WaitReason.READY  # why next_write_time answered as it did
        self.next_frame_motion_s = 0.0  # the motion of the frame next_write_time was asked about
        self.capacity_held = False  # the FIFO's bound held a frame back at least once (the job's end tells why it may have been slow)

    @property
    def lead_model_s(self) -> float:
        """The lead in model seconds: the arm runs ``pace`` times slower than the model."""
        return self.lead_s / self.estimate.pace

    def plan(self, command: Command) -> Segment:
        """The segment ``command`` would make if written next (kept for ``take``)."""
        if self.peeked is None or self.peeked[0] is not command:
            planner = self.planner
            self.peeked = (command, planner.model.plan(command, planner.pose, planner.pending_arc))
        return self.peeked[1]

    def take(self, command: Command, now: float) -> tuple[Segment, float]:
        """``command`` is written at ``now``: its segment, and when its last byte leaves the wire."""
        segment = self.plan(command)
        self.peeked = None
        planner = self.planner
        planner.pending_arc = command if isinstance(command, ArcStart) else None
        planner.pose = segment.end
        return segment, self.occupy_wire(now)

    def occupy_wire(self, now: float) -> float:
        """A frame starts on the wire at ``now`` or when the frame before has left, whichever is
        later: when its last byte leaves (every frame, the job's and a control toggle, takes its turn)."""
        start_s = max(now, self.wire_free_s)
        wire_end = start_s + self.frame_s
        self.wire_free_s = wire_end
        return wire_end

    def line_busy_until(self, until_s: float) -> None:
        """The port says bytes written before are still leaving until ``until_s`` (its
        ``out_waiting``): the next frame starts no earlier (landing times from what has left)."""
        if until_s > self.wire_free_s:
            self.wire_free_s = until_s

    def worktable_xyz(self, xyz) -> tuple[float, float, float]:
        """A reported X/Y/Z in the worktable frame of the last frame written (the frame the job
        plans in): robot coordinates less the origin when the arm reports those (status_xyz_frame)."""
        return in_frame(tuple(xyz), self.planner.pose.origin_mm) if self.reports_robot_xyz else tuple(xyz)

    def next_write_time(self, now: float, command: Command | None = None) -> float | None:
        """The earliest time ≥ now the next frame may be written if no news arrives; None while
        only new evidence can allow it (the FIFO bound is reached).

        The lead bounds the motion waiting behind the frame in progress (``waiting_seconds``):
        after an abort the arm finishes the move it is on plus at most the lead.  With
        ``command`` (the frame about to be written) its own duration counts too, so the bound
        holds after the write; without it, it is checked before the write (the queue may then
        exceed it by the frame just written).  Either way a frame is always allowed once no
        more than ``FEED_AHEAD_S`` (or the lead, if shorter) is queued in all, so the arm never
        waits for a move that is longer than the lead by itself."""
        ledger, estimate = self.ledger, self.estimate
        pending = ledger.pending
        if ledger.sent - ledger.consumed_lower_bound + 1 > self.limit_frames:  # (frames_in_flight_bound)
            self.write_reason = WaitReason.CAPACITY
            self.capacity_held = True
            return None
        wire_ok_at = self.wire_free_s - self.write_ahead_s  # handed over early, it still starts when the line is free
        if not pending:
            self.write_reason = WaitReason.WIRE if wire_ok_at > now else WaitReason.READY
            return max(now, wire_ok_at)
        if self.control_on_arrival and isinstance(command, CONTROL_COMMANDS):
            self.write_reason = WaitReason.IN_ORDER  # rule (c): only evidence lets it go
            return None
        duration_s = 0.0 if command is None else self.plan(command).duration_s
        self.next_frame_motion_s = duration_s
        ends = estimate.arm_ends()
        if ends is None:  # the estimate is the arm's time: its durations are the model's
            pace, head_end_s, tail_s = 1.0, pending[0].est_end_s, pending[-1].est_end_s
        else:
            pace, head_end_s, tail_s = estimate.pace, ends[0], ends[-1]
        # The lead in the arm's seconds: ``ends`` are the arm's, each duration × the pace (the model
        # seconds of ``lead_model_s``, the same thing measured the other way)
        lead_s, duration_s = self.lead_s / estimate.pace * pace, duration_s * pace  # (lead_model_s)
        lead_ok_at = tail_s - min(lead_s, FEED_AHEAD_S / estimate.pace * pace)  # the arm must not run dry
        if duration_s <= lead_s:
            # The waiting motion once frame j is in progress is tail − end of j: find the first
            # frame after which the new one fits within the lead; it may go once that one began.
            threshold_s = tail_s + duration_s - lead_s
            began_s = estimate.began_before(threshold_s) if ends is None else _began_before(ends, threshold_s)
            if began_s is None:
                # the new one fits behind every frame after the first once the first has begun —
                # not before: a frame written ahead (``write_ahead_s``) while the first is still on
                # the wire would leave the whole queue to run after a stop then
                began_s = max(now, head_end_s - pending[0].segment.duration_s * pace)
            lead_ok_at = min(lead_ok_at, began_s)
        when = max(now, wire_ok_at, lead_ok_at)
        if when <= now:
            self.write_reason = WaitReason.READY
        else:
            # a tie is the wire's: the frame before must leave it first whatever the lead says (a frame
            # written ahead waits for the one before to begin, which is when the line frees in virtual time)
            self.write_reason = WaitReason.LEAD if lead_ok_at > wire_ok_at + 1e-9 else WaitReason.WIRE
        return when


def _began_before(ends: list[float], threshold_s: float) -> float | None:
    """The end before the first of ``ends`` at or after ``threshold_s`` (None: the first is)."""
    began_s = None
    for end_s in ends:
        if end_s >= threshold_s:
            break
        began_s = end_s
    return began_s
