"""The time bound: when even the slowest arm allowed for has surely finished a frame.

Strategy: a chain of deadlines, one a frame (``SentFrame.certain_end_s``): a frame starts no
sooner than it landed (its last byte on the wire plus ``ARRIVAL_SLACK_S``) and no sooner than
the frame before it surely ended, and takes its model duration (plus the allowance for a path
longer than planned, ``allowance_s``) times ``slowest_factor``, plus ``frame_slack_s``.  Only
time the arm was seen running counts (kind-4 status): a reported pause stops the clock and a
resume pushes every pending deadline back by the whole pause.  A frame whose deadline the
running clock has passed is consumed by time (``advance``) — never one a RESET CONNECTOR may
have cleared, nor any once the FIFO may have been cleared (``cleared``), nor a move the arm's
reports show it standing at the start of (``standing_at``).

The chain is only ever made tighter by agreed evidence that a frame has begun (``restart``,
from the least fraction of its path both sightings allow) and only ever looser by a measured
pace (``allow_pace``: the arm slower than its profile, so every deadline moves back).  Whatever
the factor when time first confirmed a frame is kept (``least_factor_confirmed``) for the loss
check at the end of a job.
"""

from __future__ import annotations

import math

from ..motion import MotionModel, Segment
from ..protocol import ArcEnd, ArcStart, Command, RunProgram
from .constants import ARRIVAL_SLACK_S, UNVERIFIED_FK_SHARE, frame_slack_s
from .frames import Evidence, SentFrame
from .geometry import TimeMemo, start_unknown, time_window
from .ledger import Ledger


class TimeBound:
    """The slow-arm deadlines of the pending frames (see the module docstring)."""

    def __init__(self, ledger: Ledger, model: MotionModel, slowest_factor: float, memo: TimeMemo,
                 now: float) -> None:
        self.ledger, self.model, self.memo = ledger, model, memo
        self.kinematics_verified = model.profile.connector.kinematics_verified
        self.program_left_arm = False  # a PROGRAM was written, and no move since
        self.unknown_start_mm = UNVERIFIED_FK_SHARE * model.profile.workspace.reach_mm
        self.slowest_factor = slowest_factor
        self.tolerance = slowest_factor  # relative to the measured pace (``allow_pace``)
        self.least_factor_confirmed: float | None = None  # the factor in force when time first confirmed a frame
        self.frame_slack_s = frame_slack_s(slowest_factor)
        self.certain_tail_s = 0.0  # the time bound of the last frame written (even a G300's)
        # Arm-running clock: seconds the arm was certainly not paused.
        self.running_seen_s: float | None = None
        self.paused = False
        self.pause_began_s = now
        self.time_proves = True  # False once the FIFO may have been cleared (``cleared``)
        self.e_known = False  # a move has set E0/E1 since the start (``moves_e_from_the_start``)
        # the head frame the arm's last position reports show it has not begun (set by the
        # streamer from ``evidence.standing_at_start``): time does not count it done
        self.standing_at: int | None = None

    # --- a frame written ----------------------------------------------------------------------

    @staticmethod
    def begun_by_s(wire_end_s: float, before_end_s: float) -> float:
        """When a frame has surely begun: it has landed (``ARRIVAL_SLACK_S`` after its last byte
        left the wire at ``wire_end_s``) and the frame before it finished (by ``before_end_s``)."""
        return max(wire_end_s + ARRIVAL_SLACK_S, before_end_s)

    def done_by_s(self, begun_s: float, duration_s: float, frames: int = 1) -> float:
        """When ``frames`` frames with ``duration_s`` of model motion in all, begun by
        ``begun_s``, have surely finished: their motion at the slowest pace and each frame's
        handling (``frame_slack_s``).  The one statement of the rule; the job's end asks it too."""
        return begun_s + duration_s * self.slowest_factor + frames * self.frame_slack_s

    def chain(self, wire_end_s: float, duration_s: float, allowance_s: float) -> float:
        """The deadline of a frame written now, whose last byte leaves the wire at ``wire_end_s``."""
        self.certain_tail_s = self.done_by_s(self.begun_by_s(wire_end_s, self.certain_tail_s), duration_s + allowance_s)
        return self.certain_tail_s

    @staticmethod
    def group_arc(frame: SentFrame, previous: SentFrame | None) -> None:
        """The arm holds a G300 at the head until its G301 has landed and runs both as one
        segment: the G300 finishes only with the arc, whenever its G301 is written."""
        command = frame.command
        if isinstance(command, ArcStart):
            frame.certain_end_s = math.inf
        elif previous is not None and isinstance(previous.command, ArcStart) and previous.index == frame.index - 1:
            if isinstance(command, ArcEnd):
                frame.group_index = previous.index
                previous.certain_end_s = frame.certain_end_s
            else:
                previous.certain_end_s = previous.chain_end_s  # the arm skips a G300 left alone

    def allowance_s(self, segment: Segment, sent: int, anywhere: bool = False) -> float:
        """The time bound's allowance for a Cartesian move that starts where only the profile's
        kinematics say (the end of a joint move): with kinematics not verified on this arm, its
        true start may lie ``UNVERIFIED_FK_SHARE`` of the reach away, so the move may be that much
        longer than planned — covered at its own feed (half of it for a move that ramps from rest),
        held to the profile's speed limit as the plan holds it, in the model's seconds (its
        speed_factor: the durations it is added to are).  For a line that bounds it (a start r
        away makes it at most r longer).  For an arc nothing does: the circle through a start r
        away, the G300 point and the end grows without bound as that start nears the G300 point
        (tests/test_unverified_joint_end.py found a 571 mm arc overrun), so time never
        confirms it — a sighting on a later frame does, or the arm at rest at the last target
        (``confirm_all_done``, which armctl/core/job.py also applies while the FIFO bound holds the job).
        And the other way round: a joint move from the end of a Cartesian one starts at joints only
        the arm's own IK knows, anywhere within the joint limits (``joint_move_from_anywhere_s``);
        its end is exact, so its sightings hold (found: an arm 2x slower, links 5 % short, the
        probe's speed_tolerance 1.05 — a joint move the plan made 0 s long claimed done by time).
        ``sent``: the frames written before this one; ``anywhere``: the move starts where an SD
        program left the arm (``starts_where_a_program_left``): a joint move from anywhere, and a
        Cartesian one with no bound at all, as an arc above."""
        if anywhere:
            return self.model.joint_move_from_anywhere_s(segment) if segment.kind == "joint" else math.inf
        if not start_unknown(segment, self.kinematics_verified):
            return 0.0
        if segment.kind == "joint":  # (and a fixed pose) from the end of a Cartesian move
            return 0.0 if sent == 0 else self.model.joint_move_from_anywhere_s(segment)
        if segment.kind == "arc" or isinstance(segment.command, ArcEnd):  # (planned as a line when its
            return math.inf  # points coincide or line up: through the real start they need not)
        command, model = segment.command, self.model
        speed_mm_min = getattr(command, "speed_mm_min", None) or getattr(command, "speed1_mm_min", 0.0) / 2
        speed_mm_min = min(speed_mm_min, model.profile.speed.max_linear_mm_min)
        return self.unknown_start_mm / max(speed_mm_min / 60.0, 1e-3) * model.speed_factor

    def moves_e_from_the_start(self, command: Command, segment: Segment) -> bool:
        """Whether this is the first move that sets E0/E1 (every move carries them) and moves them
        as planned.  No status kind reports them, so where they start is unknown — the reported
        start pose takes the profile's 0, the arm's state at power-on — and that move may need
        any time for them: none (an arm whose axes stand at its targets already: a 2.6 s move of
        U240 planned, none run, and the job 'finished early'), or more than planned (from farther
        away: the arm then looks slower than the model).  So its time is not known
        (``SentFrame.timing_known``), the loss checks count none of it, and time never confirms it
        (as an arc from an unknown start): a later frame's sighting does, or the arm at rest."""
        if self.e_known or segment.kind == "still" or not hasattr(command, "e0_deg"):
            return False
        self.e_known = True
        start = segment.start
        return (start.e0_deg, start.e1_deg) != (command.e0_deg, command.e1_deg)

    def program_time_unknown(self, command: Command) -> bool:
        """Whether ``command`` runs an SD program (PROGRAM n): the program runs for as long as it
        says, which armctl cannot see (the motion model gives it none), so its time is not known
        (``SentFrame.timing_known``) and time never confirms it — on an arm whose control frames
        queue (H5) the program holds the FIFO meanwhile (a bound that took it for 0 s let the host
        write on into a full FIFO), and on one where they act as they land the next control frame
        would cut it short.  The arm's reports confirm it: a later frame's sighting (the arm runs
        its frames in order), or it worked after the frame landed and rests since
        (armctl/core/job_program.py)."""
        return isinstance(command, RunProgram)

    def starts_where_a_program_left(self, command: Command, segment: Segment) -> bool:
        """Whether this is the first move written after a PROGRAM: it starts wherever the SD
        program left the arm, which the plan cannot know (it has the arm where it was), so its path
        is not the planned one and its time bound allows a start anywhere (``allowance_s``): a
        bound from the planned start could count it done while it still runs (and, on an arm
        whose control frames act as they land, let the control frame after it cut it short)."""
        if self.program_time_unknown(command):
            self.program_left_arm = True
            return False
        if not self.program_left_arm or segment.kind not in ("joint", "line", "arc"):
            return False
        self.program_left_arm = False
        return True

    # --- the running clock ----------------------------------------------------------------------

    def note_pause_state(self, paused: bool, now: float) -> None:
        """A kind-4 status: the running clock advances to ``now`` unless the arm is paused."""
        if paused and not self.paused and self.running_seen_s is not None:
            self.pause_began_s = self.running_seen_s  # it may have begun right after
        if not paused:
            if self.paused:
                # Everything still pending waited at least from the last sighting of a running
                # arm to now: push the certain end times back by that much.
                shift = now - self.pause_began_s
                for sent in self.ledger.pending:
                    sent.certain_end_s += shift
                    sent.chain_end_s += shift
                self.certain_tail_s += shift
            self.running_seen_s = now
        self.paused = paused

    def cleared(self) -> None:
        """The FIFO may have been cleared: from now on time confirms nothing."""
        self.time_proves = False

    def advance(self) -> None:
        """Consume every frame at the head whose deadline the running clock has passed."""
        if self.running_seen_s is None or self.paused or not self.time_proves:
            return
        certain_now = self.running_seen_s
        ledger = self.ledger
        pending = ledger.pending
        # (a frame a RESET CONNECTOR may have cleared has no time to finish in: reports decide it)
        while (pending and pending[0].certain_end_s <= certain_now and not pending[0].may_be_cleared
               and pending[0].index != self.standing_at):
            if ledger.confirmed_by_time == 0:
                self.least_factor_confirmed = self.slowest_factor
            ledger.consume_one(by_reports=False)
            ledger.bound_evidence = Evidence.TIME

    # --- evidence moves the chain -----------------------------------------------------------------

    def restart(self, index: int, now: float, fraction: float = 0.0) -> None:
        """Frame ``index`` has begun by ``now`` and its arm is at least ``fraction`` along its path
        (agreed evidence): restart the chain there, since a chain that began at the first frame
        of a long job drifts ahead by the slowest-arm factor for as long as the arm is kept busy."""
        pending = self.ledger.pending
        if not pending:
            return
        chain = None
        done_by_s, begun_by_s = self.done_by_s, self.begun_by_s
        for k in range(index - pending[0].index, len(pending)):
            if k < 0:
                return  # that frame is already known finished: nothing about the next ones
            sent = pending[k]
            if chain is None:  # the rest of it, from the least fraction the evidence allows
                left_s = sent.segment.duration_s - time_window(sent.segment, fraction, 1.0, self.memo.time_at)[0]
                chain = done_by_s(now, left_s + sent.unknown_start_s)
            else:
                chain = done_by_s(begun_by_s(sent.wire_end_s, chain), sent.segment.duration_s + sent.unknown_start_s)
            if chain >= sent.chain_end_s:
                return  # no tighter than before, and neither are the frames after it
            sent.chain_end_s = chain
            if not isinstance(sent.command, ArcStart):
                sent.certain_end_s = chain
                if sent.group_index != sent.index and k > 0:
                    pending[k - 1].certain_end_s = chain  # its G300 finishes with it
            elif k + 1 < len(pending) and pending[k + 1].group_index != sent.index:
                sent.certain_end_s = chain  # a G300 not followed by its G301: skipped
        self.certain_tail_s = chain

    def at_rest(self, now: float) -> None:
        """The arm was seen at rest with every frame done (mid-job): the chain starts again now."""
        pending = self.ledger.pending
        if pending:
            self.restart(pending[0].index, now)  # the held G300 is at the head
        else:
            self.certain_tail_s = min(self.certain_tail_s, now)

    def allow_pace(self, pace: float) -> None:
        """An arm measured slower than its profile's speed_factor: the time bound allows that much
        more from here on (only ever more careful; whatever it confirmed before is judged by
        ``Losses.check_slowness``)."""
        wider = self.tolerance * pace
        if wider > self.slowest_factor:
            self.widen(wider)

    def widen(self, factor: float) -> None:
        """From now on the time bound allows an arm ``factor`` times slower than the model; the
        pending frames' deadlines move back by what the wider factor adds to each of them and to
        every pending frame before it (a chain can only end later, never earlier)."""
        extra = factor - self.slowest_factor
        self.slowest_factor = factor
        added_s = 0.0
        for sent in self.ledger.pending:
            added_s += (sent.segment.duration_s + sent.unknown_start_s) * extra
            sent.chain_end_s += added_s
            sent.certain_end_s += added_s  # inf (a G300 waiting for its G301) stays inf
        self.certain_tail_s += added_s
