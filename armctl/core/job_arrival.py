"""Where the arm rests, against the frames written: what its reports prove ran, and where a
stopped job resumes.

Strategy: pure questions over the record (armctl/core/job_readings.py: the arm's readings, the
frames written) and the streamer's frames still pending; the only state here is what the arm
has shown of itself (``found_arrival``) and where the resume goes (``resume_at_next``).  What
each may conclude, from what evidence:

- ``at_end_of(segment)``: the arm reports a frame's end — in joints for a joint move or a pose
  only the profile's kinematics turned into X/Y/Z, else in X/Y/Z — within a reading's
  resolution (``TARGET_MM``, ``TARGET_DEG``).  Never in a pose the arm did not report.
- ``may_read_as_end_of``: whether a rest at some pose could pass for a frame's end: it cannot
  only where both are known in the readings compared (not derived through unverified
  kinematics), in the same worktable, and more than twice the tolerance apart.
- ``arm_at_rest(now)``: at rest by armctl/core/evidence.py's rule, no SD program advancing, and the
  estimate over.
- ``program_ended``: an SD program (a PROGRAM frame whose time only the arm's reports can end,
  ``Streamer.program_time_unknown``) ran and ended: the arm worked after the frame landed
  (``Readings.worked_after``) and is at rest now (``arm_at_rest``), not paused.  Wherever it
  rests: the program moves the arm as it says.
- ``frozen_mid_move``: paused and still strictly inside the path of a frame still pending, at
  no frame's end: only a pause that acts as it lands (H5 "arrival") freezes a move there — a
  queued pause, or an arm that dropped frames, leaves it at some frame's end.  The proof that
  an arm profiled as queued acts on arrival (``found_arrival``).
- ``confirm_through_last_move``: paused on an arm that acts on arrival: the moves whose ends it
  reached ran; the frames after its last move (a PWM change, a delay) leave no trace and are
  not claimed.  ``frozen_at_a_boundary`` then says the resume is the next frame.
- ``done_at(now)``: when the arm finished — the end of its last motion seen, where the
  estimate lies in the window the reports leave (the kinds of a rotation come 210 ms apart),
  plus the model's time of the frames after it that move nothing.
"""

from __future__ import annotations

from .job_readings import TARGET_DEG, TARGET_MM, changes_readings, landed_s, moves_arm, values_text
from .evidence import REST_CHECK_S
from .motion import distance_to_path
from .protocol import CONTROL_COMMANDS, ArcEnd, GoToPose, RunProgram


class Arrival:
    """The arm's rest judged against the frames written (``readings``, ``written``) and the
    frames the ``streamer`` still counts as pending."""

    def __init__(self, readings, written, streamer) -> None:
        self.readings = readings
        self.written = written
        self.streamer = streamer
        self.found_arrival = False  # the arm proved its control frames act as they land (``frozen_mid_move``)
        self.resume_at_next = False  # frozen where the first pending frame ends and the next begins
        readings.on_rest = self.rested

    def rested(self, through: int, now: float) -> None:
        """The arm at rest at ``now`` where only frames through ``through`` can have left it
        (``Written.rests_at``, while a frame nothing else judges holds the lower bound back): they
        ran, and are confirmed so (no chain restart: the next frame may not have landed)."""
        streamer = self.streamer
        streamer.confirm_all_done(before=through + 1)
        self.written.done(streamer.consumed_lower_bound, now)

    @property
    def acts_on_arrival(self) -> bool:
        """The arm's control frames act as they land: the profile says so, or the arm showed it."""
        return self.streamer.control_on_arrival or self.found_arrival

    def arm_at_rest(self, now: float) -> bool:
        """The arm reported the same position, joints and PWM for REST_CHECK_S and the estimate
        says the job is over."""
        finish = self.streamer.estimated_finish_s()
        if finish is not None and now < finish:
            return False
        readings = self.readings
        if readings.active_s is not None and now - readings.active_s < REST_CHECK_S:
            return False  # an SD program still advancing, even with the arm standing still
        return readings.rest_s() >= REST_CHECK_S

    def program_ended(self, sent, now: float) -> bool:
        """The arm's reports show the SD program of ``sent`` (a PROGRAM frame) ran and ended: the
        arm worked after the frame landed and rests since, not paused (module docstring)."""
        readings = self.readings
        return (readings.worked_after(landed_s(sent)) and self.arm_at_rest(now)
                and readings.paused is False)

    def at_last_target(self) -> bool:
        """The arm reports the end of the last frame written (joints for a joint move)."""
        recent = self.written.recent
        if not recent:
            return True
        return self.at_end_of(recent[-1].segment)

    def at_end_of(self, segment) -> bool:
        """The arm reports the end of ``segment`` (joints for a joint move)."""
        if segment.kind == "joint" or segment.end.xyz_derived:  # what the arm reports, not the profile's FK
            joints = self.readings.joints
            return len(joints) == 6 and max(abs(a - b) for a, b in zip(joints, segment.end.joints)) <= TARGET_DEG
        position = self.readings.position
        return position is not None and max(abs(a - b) for a, b in zip(position, segment.end.xyz)) <= TARGET_MM

    def may_read_as_end_of(self, pose, segment) -> bool:
        """Whether an arm at rest at the model's ``pose`` may report what ``at_end_of(segment)``
        takes for the end of ``segment``.  It cannot only where the pose is known in the readings
        compared (not derived through the profile's unverified kinematics), in the same worktable,
        and more than twice their tolerance away."""
        end, verified = segment.end, self.streamer.kinematics_verified
        if pose.origin_mm != end.origin_mm:
            return True
        if segment.kind == "joint" or end.xyz_derived:
            if pose.joints_derived and not verified:
                return True
            return max(abs(a - b) for a, b in zip(pose.joints, end.joints)) <= 2 * TARGET_DEG
        if pose.xyz_derived and not verified:
            return True
        return max(abs(a - b) for a, b in zip(pose.xyz, end.xyz)) <= 2 * TARGET_MM

    def moved_past(self, run: list) -> bool:
        """The reports prove the arm is past ``run``, frames that move nothing and change no
        reading (``changes_readings``: no G54, no path unknown): it moved after every frame before
        them was known finished (``Readings.worked_after``: a change two reports agree on, from a
        value read after that).  A change proves motion whatever frame the readings are in; a
        difference from a pose would not (an unprobed arm's X/Y/Z may be in another frame than
        the profile says).  An 8-frame FIFO's job once waited for ever at POSE 2, the arm taken to
        be maybe resting in the PWM-only move before it."""
        if any(changes_readings(sent) for sent in run):
            return False
        since_s = self.written.finished_s(run[0].index)
        return since_s is not None and self.readings.worked_after(since_s)

    def done_at(self, now: float) -> float:
        """When the arm finished: the end of its last motion seen, plus the model's time for
        the frames after that motion, which move nothing (delays, M codes, control frames,
        PWM-only moves, a move to where the arm already is); never before the last change
        seen at all (a PWM report), never after now."""
        readings = self.readings
        if readings.motion is None:  # set with ``rest``: nothing reported yet
            return now
        # every frame after the last one that moves, however many (not only the recent ones)
        last = self.written.last_move
        moved_until_s = 0.0 if last is None else last.motion_before_s + last.segment.duration_s
        trailing_s = self.streamer.motion_sent_s - moved_until_s
        _, seen_s, moving_s = readings.motion
        done = max(seen_s + trailing_s, readings.changed_s, readings.active_s or 0.0)
        if moving_s is not None and last is not None and done == seen_s + trailing_s:
            # Every kind of reading had its last value by ``seen_s``, and one still differed from
            # it at ``moving_s`` (the latest such reading): the arm stopped in between, up to a
            # rotation before ``seen_s`` (kinds 0-2 come together, then 210 ms of others), so the
            # end is the estimate's where it lies in that window, else its middle (``seen_s`` made
            # a 2.63 s job read 2.79 s at 115200 baud).
            end_s = last.est_end_s
            done = (end_s if moving_s <= end_s <= seen_s else (moving_s + seen_s) / 2) + trailing_s
        program = self.written.last_program
        if (program is not None and readings.program_active_s is not None
                and (last is None or program.index > last.index)):
            # the frames after an SD program that move nothing (a delay …) run once it ends,
            # which its run position last advancing shows (the model gives the program no time:
            # ``trailing_s`` leaves it out; frames that move the arm are dated by their motion)
            after_s = self.streamer.motion_sent_s - program.motion_before_s - program.segment.duration_s
            done = max(done, readings.program_active_s + after_s)
        return min(done, now)

    def arms_own_motion_last(self) -> str | None:
        """Why the arm is not at the last target when the job's last positioning frame is one
        whose motion is the arm's own, not the job's: a ``POSE n`` goes to the arm's fixed pose,
        which the profile's ``[poses]`` only describe, and a ``PROGRAM n`` runs an SD program
        armctl cannot see into.  Named as such (None when no such frame comes after the job's own
        last motion): the arm's rest elsewhere is no sign that frames were lost."""
        for sent in reversed(self.written.recent):
            command = sent.command
            where = f"line {sent.tag.line}" if getattr(sent.tag, "line", None) is not None else f"frame {sent.index + 1}"
            if isinstance(command, RunProgram):
                return (f"the arm stopped at ({values_text(self.readings.position)}) after PROGRAM {command.program} "
                        f"({where}): an SD program moves the arm as it says, which armctl cannot know, so where it "
                        "rests proves nothing about the job's frames")
            if isinstance(command, GoToPose):
                return (f"POSE {command.pose} ({where}) should end at the profile's fixed pose {command.pose} (joints "
                        f"{values_text(sent.segment.end.joints)}), but the arm stopped at joints "
                        f"({values_text(self.readings.joints)}): its own fixed pose {command.pose} is not the profile's "
                        f"[poses] (or the frame did not run)")
            if moves_arm(sent.segment):
                return None  # the job's own move after it says where the arm should be
        return None

    def confirm_through_last_move(self) -> None:
        """The arm at rest at the end of the last frame written that moves it (its target where no
        other frame kept ends or it starts: ``Streamer.ran_at_rest``): it and every frame before it ran."""
        streamer = self.streamer
        last = self.written.last_move
        if last is not None and self.at_end_of(last.segment) and streamer.ran_at_rest(last):
            last.seen = True
            streamer.confirm_all_done(before=last.index + 1)
            return
        # Else the first pending frame whose path holds where the arm rests: at its end, its motion
        # is over (the arm is there, or on a later frame), so it is not re-sent; anywhere else on
        # it, the arm is frozen in it.  Judged in what the arm reports, frame by frame in order,
        # up to a frame whose pose that cannot judge.
        position, joints = self.readings.position, self.readings.joints
        verified, origin = streamer.kinematics_verified, streamer.planner.pose.origin_mm
        for sent in streamer.pending:
            segment = sent.segment
            by_joints = segment.kind == "joint" or segment.kind == "still" and not segment.end.joints_derived
            if not sent.path_known or (segment.end.joints_derived if by_joints else segment.end.xyz_derived) and not verified:
                return
            if not by_joints and (segment.start.origin_mm != origin or segment.end.origin_mm != origin):
                return  # X/Y/Z read in the last worktable, its path in another (a G54 between)
            observed, near = (joints, TARGET_DEG) if by_joints else (position, TARGET_MM)
            if observed is None or len(observed) != (6 if by_joints else 3):
                return
            if distance_to_path(segment, observed)[0] > near:
                continue
            end = segment.end.joints if by_joints else segment.end.xyz
            if moves_arm(segment) and max(abs(a - b) for a, b in zip(end, observed)) <= near:
                streamer.confirm_all_done(before=sent.index + 1)
            return

    def frozen_mid_move(self) -> bool:
        """The arm, paused and still, rests strictly inside the path of a frame still pending — at
        no frame's end, where a pause queued behind the frames (H5) would leave it (an arm that
        dropped frames too): only a pause that acted as it landed freezes a move there.  Judged
        on what the arm reports: X/Y/Z on a line or arc, joints on a joint move, each on a path
        the plan knows."""
        position, joints = self.readings.position, self.readings.joints
        streamer = self.streamer
        ends = [sent.segment for sent in self.written.recent] + list(sent.segment for sent in streamer.pending)
        origin = streamer.planner.pose.origin_mm  # the worktable the readings are turned into (worktable_xyz)
        for sent in streamer.pending:
            segment = sent.segment
            if not sent.path_known or segment.length <= 0:
                continue
            cartesian = segment.kind in ("line", "arc")
            if cartesian and not segment.end.xyz_derived and position is not None:
                observed, near = position, TARGET_MM
            elif segment.kind == "joint" and len(joints) == 6:
                observed, near = joints, TARGET_DEG
            else:
                continue
            if distance_to_path(segment, observed)[0] > near:
                continue
            for other in ends:  # at no frame's end (nor the first pending frame's start)
                for pose in (other.start, other.end):
                    if pose.origin_mm != origin:
                        return False  # a G54 among them: the readings are in one worktable, not in both
                    if (pose.xyz_derived if cartesian else pose.joints_derived) and not streamer.kinematics_verified:
                        return False  # where that pose really is only the arm knows: no proof
                    if max(abs(a - b) for a, b in zip(pose.xyz if cartesian else pose.joints, observed)) <= 2 * near:
                        return False
            return True
        return False

    def proves_arrival(self) -> bool:
        """True the first time the arm, paused and still, is frozen mid-move (``frozen_mid_move``):
        its control frames act as they land, whatever the profile says (``found_arrival``)."""
        if self.found_arrival or not self.frozen_mid_move():
            return False
        self.found_arrival = True
        return True

    def settle_paused(self) -> None:
        """Paused by a pause that acted as it landed: the moves whose ends the arm reached ran
        (``confirm_through_last_move``), and frozen at a boundary the resume goes to the next
        frame (``frozen_at_a_boundary``)."""
        self.confirm_through_last_move()
        self.resume_at_next = self.frozen_at_a_boundary()

    def frozen_at_a_boundary(self) -> bool:
        """A pause that acted as it landed froze the arm at the end of the first pending frame
        (or on it, if it moves nothing), i.e. at the start of the next, a move: either is the
        frozen one.  The resume toggle finishes it, so the resume line is the next frame: run
        once if the arm was on the first, re-sent to where the arm then is (idempotent) if it was
        on the next.  (Resuming at the first would drive the arm back to its end after the next
        had finished.)"""
        pending = self.streamer.pending
        if len(pending) < 2 or not moves_arm(pending[1].segment) or isinstance(pending[1].command, CONTROL_COMMANDS):
            return False
        return self.at_end_of(pending[0].segment)  # a first frame that moves nothing: the arm is at its end

    def first_not_done(self, view):
        """The statement to resume at: the first not known finished (an arc's G301 resumes at its
        G300; frozen at a boundary, the next frame)."""
        pending = self.streamer.pending
        if self.resume_at_next and len(pending) > 1:
            return pending[1].tag
        if not pending:
            return view.next_statement
        if isinstance(pending[0].command, ArcEnd) and view.last_done is not None:
            return view.last_done  # a G301 cannot be resumed alone: resume at its G300
        return pending[0].tag
