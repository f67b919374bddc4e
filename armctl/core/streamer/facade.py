"""``Streamer``: the one object its callers hold; it routes each event to the parts that own it.

Strategy: no rule of its own.  A write goes to the gate (plan, wire), the time bound (its
deadline), the estimate (its end), the evidence (what each stream may judge) and the ledger;
a status frame to the evidence, whose ``Sighting`` then moves the ledger (agreed), the time
bound's chain (agreed), the pace and the loss checks (agreed, on one frame) and the estimate
(any).  The callers' names (job.py, runner.py, the bench, the tests) read through to the part
that owns each fact (``_part``).
"""

from __future__ import annotations

import math
from operator import attrgetter

from ..motion import ArmPose, MotionModel, Segment
from ..protocol import ArcStart, Command, DEFAULT_BAUD, JointsHighStatus, JointsLowStatus, PauseStatus
from ..protocol import PositionStatus, StatusFrame, frame_seconds
from .constants import CAPACITY_MARGIN_FRAMES, DEFAULT_LEAD_S, PACE_FOLLOWED, limit_frames
from .estimate import Estimate
from .evidence import Sighting, Sightings, ran_at_rest, standing_at_start
from .frames import Evidence, SentFrame, where
from .gate import Gate
from .geometry import TimeMemo, start_unknown
from .ledger import Ledger
from .losses import Losses
from .time_bound import TimeBound

_POSITION_KIND, _JOINTS_LOW_KIND, _JOINTS_HIGH_KIND, _PAUSE_KIND = (
    PositionStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND, PauseStatus.KIND)


def _part(part: str, name: str, writable: bool = True) -> property:
    """The façade's name for ``part.name`` (read, and written when the callers write it)."""

    def set_value(self, value) -> None:
        setattr(getattr(self, part), name, value)

    return property(attrgetter(f"{part}.{name}"), set_value if writable else None)


class Streamer:
    """Decides when the next frame may be written; see the package docstring."""

    def __init__(
        self,
        model: MotionModel,
        start: ArmPose,
        *,
        lead_s: float = DEFAULT_LEAD_S,
        capacity: int | None = None,
        margin: int = CAPACITY_MARGIN_FRAMES,
        baud: int = DEFAULT_BAUD,
        slowest_factor: float | None = None,
        now: float = 0.0,
        write_ahead_s: float = 0.0,
    ) -> None:
        """``capacity``: frames the connector holds behind the one executing (None: the profile's
        ``[connector] fifo_frames``); ``slowest_factor``: how many times slower than the model the
        arm may run (None: the profile's ``[connector] speed_tolerance``); ``write_ahead_s``: how
        long before the line is free the next frame may be handed to the port (a wall-clock host's
        buffer against its own wake-up jitter; 0 in virtual time, where nobody is late)."""
        connector = model.profile.connector
        slowest = connector.speed_tolerance if slowest_factor is None else slowest_factor
        self.kinematics_verified = connector.kinematics_verified
        memo = TimeMemo()
        self._ledger = Ledger(connector.control_on_arrival)
        self._estimate = Estimate(self._ledger, memo)
        self._gate = Gate(self._ledger, self._estimate, model, start, lead_s=lead_s,
                          limit_frames=limit_frames(connector.fifo_frames if capacity is None else capacity, margin),
                          frame_s=frame_seconds(baud), now=now, write_ahead_s=write_ahead_s)
        self._bound = TimeBound(self._ledger, model, slowest, memo, now)
        self._evidence = Sightings(self._ledger, memo, connector.kinematics_verified, connector.reports_robot_xyz,
                                   self._bound.unknown_start_mm)
        self._losses = Losses(self._ledger, memo, slowest, connector.kinematics_verified)
        self.status_frames = 0

    # The callers' names for the parts' facts.
    pending = _part("_ledger", "pending", False)
    sent = _part("_ledger", "sent", False)
    consumed_lower_bound = _part("_ledger", "consumed_lower_bound", False)
    frames_in_flight_bound = _part("_ledger", "frames_in_flight_bound", False)
    bound_evidence = _part("_ledger", "bound_evidence", False)
    confirmed_by_reports = _part("_ledger", "confirmed_by_reports", False)
    confirmed_by_time = _part("_ledger", "confirmed_by_time", False)
    confirmed_unseen = _part("_ledger", "confirmed_unseen", False)
    first_time_only_index = _part("_ledger", "first_time_only_index", False)
    fifo_holds_all = _part("_ledger", "fifo_holds_all")
    motion_sent_s = _part("_ledger", "motion_sent_s", False)
    sure_motion_sent_s = _part("_ledger", "sure_motion_sent_s", False)
    planner = _part("_gate", "planner", False)
    control_on_arrival = _part("_gate", "control_on_arrival", False)
    reports_robot_xyz = _part("_gate", "reports_robot_xyz", False)
    lead_s = _part("_gate", "lead_s", False)
    lead_model_s = _part("_gate", "lead_model_s", False)
    limit_frames = _part("_gate", "limit_frames", False)
    frame_s = _part("_gate", "frame_s", False)
    wire_free_s = _part("_gate", "wire_free_s")
    write_ahead_s = _part("_gate", "write_ahead_s")
    write_reason = _part("_gate", "write_reason", False)
    next_frame_motion_s = _part("_gate", "next_frame_motion_s", False)
    capacity_held = _part("_gate", "capacity_held", False)
    slowest_factor = _part("_bound", "slowest_factor", False)
    frame_slack_s = _part("_bound", "frame_slack_s", False)
    pace = _part("_estimate", "pace", False)
    plan_changes = _part("_estimate", "plan_changes", False)
    losses = _part("_losses", "losses", False)
    first_suspect_index = _part("_losses", "first_suspect_index")
    fastest_factor = _part("_losses", "fastest_factor", False)
    slowest_proven = _part("_losses", "slowest_proven", False)
    moved_past_bound = _part("_losses", "moved_past_bound", False)

    # --- writing ----------------------------------------------------------------------------

    def next_write_time(self, now: float, command: Command | None = None) -> float | None:
        """The earliest time ≥ now the next frame may be written if no news arrives; None while
        only new evidence can allow it (``Gate.next_write_time``)."""
        return self._gate.next_write_time(now, command)

    def may_write(self, now: float, command: Command | None = None) -> bool:
        when = self._gate.next_write_time(now, command)
        return when is not None and when <= now

    def plan(self, command: Command) -> Segment:
        """The segment ``command`` would make if written next (kept for ``wrote``)."""
        return self._gate.plan(command)

    def line_busy_until(self, until_s: float) -> None:
        self._gate.line_busy_until(until_s)

    def worktable_xyz(self, xyz) -> tuple[float, float, float]:
        return self._gate.worktable_xyz(xyz)

    def queued_seconds(self, now: float) -> float:
        return self._estimate.queued_seconds(now)

    def waiting_seconds(self, now: float) -> float:
        return self._estimate.waiting_seconds(now)

    def moved_past_time_bound(self, moved_after_s: float | None, bound_s: float) -> None:
        """The job's end: the arm moved after ``moved_after_s``, every frame written surely done by
        ``bound_s`` (``Losses.moved_past_time_bound``)."""
        self._losses.moved_past_time_bound(moved_after_s, bound_s)

    def loss_found(self, sentence: str, suspect: int) -> None:
        """The caller (the job's end) found a sign of loss: it joins the streamer's own."""
        self._losses.found(sentence, suspect)

    def done_by_s(self, begun_s: float, duration_s: float, frames: int = 1) -> float:
        """When ``frames`` frames with ``duration_s`` of model motion in all, begun by ``begun_s``,
        have surely finished, even on the slowest arm allowed for (``TimeBound.done_by_s``)."""
        return self._bound.done_by_s(begun_s, duration_s, frames)

    begun_by_s = staticmethod(TimeBound.begun_by_s)

    def program_time_unknown(self, command: Command) -> bool:
        """Only the arm's reports can say when this SD program ended (``TimeBound.program_time_unknown``)."""
        return self._bound.program_time_unknown(command)

    def wrote_control(self, now: float) -> None:
        """A frame that is not the job's (a pause toggle) went on the wire at ``now``: it holds
        the line for one frame time, as the job's frames do."""
        self._gate.occupy_wire(now)

    def wrote(self, command: Command, now: float, tag: object = None) -> SentFrame:
        """Record that the next frame's first byte went on the wire at ``now``."""
        ledger, bound = self._ledger, self._bound
        index = ledger.sent
        segment, wire_end = self._gate.take(command, now)
        anywhere = bound.starts_where_a_program_left(command, segment)
        time_unknown = bound.moves_e_from_the_start(command, segment) or bound.program_time_unknown(command)
        allowance_s = math.inf if time_unknown else bound.allowance_s(segment, index, anywhere)
        previous = ledger.pending[-1] if ledger.pending else None
        certain_end_s = bound.chain(wire_end, segment.duration_s, allowance_s)
        frame = SentFrame(
            index=index, command=command, segment=segment, tag=tag, wire_end_s=wire_end,
            certain_end_s=certain_end_s, chain_end_s=certain_end_s, group_index=index,
            motion_before_s=ledger.motion_sent_s, unknown_start_s=allowance_s,
            sure_before_s=ledger.sure_motion_sent_s, sure_s=0.0 if allowance_s else segment.duration_s,
            timing_known=not time_unknown,  # (every path_known False frame has an allowance)
            path_known=not (index > 0 and (anywhere or start_unknown(segment, self.kinematics_verified))),
        )
        self._estimate.written(frame, previous)
        bound.group_arc(frame, previous)
        self._evidence.written(frame)
        ledger.record(frame, command)
        return frame

    # --- reading ----------------------------------------------------------------------------

    def receive_status(self, frame: StatusFrame, now: float) -> None:
        """Take one status frame read at ``now``."""
        self.status_frames += 1
        kind = frame.KIND  # (every status frame: one test a kind, the rest only counted)
        if kind == _POSITION_KIND:
            found = self._evidence.position((frame.x_mm, frame.y_mm, frame.z_mm), now)
            if found is not None:
                self._take(found, now)
            pending, bound = self._ledger.pending, self._bound
            standing = standing_at_start(found, pending) if bound.time_proves else None  # (not once cleared)
            # (elsewhere: this report and the one before agree, not on the start; None twice too)
            left = standing is None and found is not None and found.previous == found.earliest
            bound.standing_at = self._losses.check_not_begun(standing, pending[0] if pending else None, now,
                                                             None if bound.paused else bound.running_seen_s, left)
        elif kind == _JOINTS_LOW_KIND:
            found = self._evidence.joint_half(0, (frame.j1_deg, frame.j2_deg, frame.j3_deg), now)
            if found is not None:
                self._take(found, now)
        elif kind == _JOINTS_HIGH_KIND:
            found = self._evidence.joint_half(3, (frame.j4_deg, frame.j5_deg, frame.j6_deg), now)
            if found is not None:
                self._take(found, now)
        elif kind == _PAUSE_KIND:
            if frame.paused:
                self._estimate.paused()
                self._losses.paused()
            self._bound.note_pause_state(frame.paused, now)
        pending, running_s = self._ledger.pending, self._bound.running_seen_s
        if pending and running_s is not None and pending[0].certain_end_s <= running_s:
            self._bound.advance()  # (its first tests inline: every status frame)

    def _take(self, found: Sighting, now: float) -> None:
        """Act on one matched report: an agreed one moves the lower bound, the time bound's chain,
        the pace and the loss checks; any moves the estimate."""
        estimate = self._estimate
        if found.beyond:
            estimate.reanchor_beyond(found.match, found.end, now)
            return
        stream, earliest, candidates = found.stream, found.earliest, found.candidates
        if stream == "position":
            self._losses.check_reversal(found.off_path_xyz, found.match)
        if earliest is None:
            return
        previous = found.previous
        if previous is not None:
            agreed = min(previous, earliest)
            could_be_on = found.could_be_on
            if could_be_on is not None:
                self._losses.sighted(stream, previous, earliest, now, could_be_on)
            ledger = self._ledger
            before = ledger.consumed_lower_bound
            ledger.consume_before(agreed)
            if ledger.consumed_lower_bound > before:
                ledger.bound_evidence = Evidence.POSITION if stream == "position" else Evidence.JOINTS
            self._bound.restart(agreed, now, found.least_fraction)
            if agreed == earliest:
                window = estimate.pace_window(stream, earliest, candidates)
                if window is not None:
                    sent, lo, hi = window
                    if could_be_on is not None:
                        self._losses.check_slowness(stream, earliest, sent.segment, lo, hi, now, could_be_on)
                    if estimate.sample_pace(stream, sent, lo, hi, now):
                        self._bound.allow_pace(estimate.pace)
        if not found.settled:
            estimate.reanchor(candidates, now)
        if estimate.pace >= PACE_FOLLOWED:
            estimate.pin_estimate(candidates, now)

    def _scan(self, match, end: int, now: float):
        """``Sightings.scan``: (earliest, candidates) of one observation."""
        return self._evidence.scan(match, end, now)

    def cleared(self) -> None:
        """The connector may have discarded the frames still queued (a RESET CONNECTOR that acts
        as it lands): the time bound assumes every frame written waits in the FIFO, so from now
        on only the arm's reports confirm a pending frame."""
        self._bound.cleared()
        self._ledger.cleared()

    # --- the end of a job ---------------------------------------------------------------------

    def estimated_finish_s(self) -> float | None:
        return self._estimate.estimated_finish_s()

    @property
    def all_consumed(self) -> bool:
        """Every frame written is known to have finished."""
        return not self._ledger.pending

    def confirm_all_done(self, now: float | None = None, before: int | None = None,
                         evidence: Evidence = Evidence.AT_REST) -> None:
        """The caller saw the arm at rest at the last frame's target: every frame written has
        run — except a trailing G300, which the arm holds until its G301 comes.  Sound only on
        the caller's proof (armctl/core/job.py): every status kind re-read unchanged, and no frame
        that moves nothing (where the arm rests too) left before the last motion unproven.
        With ``now`` (the proof taken mid-job, more to be written) the time bound's chain starts
        again there: it may have run to infinity behind an arc it cannot bound.  With ``before``
        (mid-job too: the arm rests in that frame or later) only the frames before it.  ``evidence``:
        the caller's proof, as the bound's evidence tells it (an SD program seen to end, ``PROGRAM_ENDED``)."""
        ledger = self._ledger
        pending = ledger.pending
        last = ledger.recent_sent[-1] if ledger.recent_sent else None  # the last frame written, pending or not
        if last is not None and (before is None or last.index < before) and self.ran_at_rest(last):
            ledger.proven_run(last)
            if last.group_index != last.index and len(pending) > 1:
                pending[-2].seen = True  # its G300
        while pending and (before is None or pending[0].index < before) and not (
                len(pending) == 1 and isinstance(pending[0].command, ArcStart)):
            # a frame that leaves no trace (unless seen): the caller's proof of it is time
            ledger.consume_one(by_reports=pending[0].seen or pending[0].segment.moves_reported, at_rest=True)
            ledger.bound_evidence = evidence
        if now is not None:
            self._bound.at_rest(now)

    def runs_unproven(self) -> list[str]:
        """Why FINISHED would claim more than the reports prove: straight moves whose refusal the
        not-begun sign could not see (or, short, no sign at all), consumed with no report to prove
        they ran (``Ledger.prove_ran``)."""
        ledger = self._ledger
        moves, count = ledger.runs_unproven, ledger.runs_unproven_count
        if ledger.awaiting is not None:  # (the job's last frame: nothing after it to prove it by)
            moves, count = moves + [ledger.awaiting], count + 1
        if not moves:
            return []
        more = f" and {count - len(moves)} more" if count > len(moves) else ""
        return [f"no report showed the arm run {', '.join(where(sent) for sent in moves)}{more}: a move whose target "
                "the profile's kinematics put out of the arm's reach, or whose start only they know (after a joint "
                "move, a POSE or an SD program), or with such a frame queued behind it, where a target out of the "
                "arm's reach, refused, would look the same"]

    def ran_at_rest(self, last: SentFrame) -> bool:
        """Whether the arm at rest at the target of ``last`` proves it ran (``evidence.ran_at_rest``)."""
        return ran_at_rest(last, self._ledger.recent_sent, self.kinematics_verified)

    def check_time_bound(self) -> None:
        """A sign of loss told at the end of a job (``Losses.check_time_bound``)."""
        self._losses.check_time_bound(self._bound.least_factor_confirmed, self._bound.time_proves)

    def tag_of(self, index: int):
        """The tag of frame ``index`` if it is among the frames kept, else None."""
        return self._ledger.tag_of(index)

    def last_known_done(self):
        """The tag of the last frame known finished, or None."""
        return self._ledger.last_done_tag
