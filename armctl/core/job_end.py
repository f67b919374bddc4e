"""When a streamed job is over, and how it ended: the proofs the job engine (armctl/core/job.py)
needs to stop waiting, and the outcomes they allow.

Strategy: pure questions over the record (armctl/core/job_readings.py) and the arm's arrival
(armctl/core/job_arrival.py), with ``now`` passed in; the state here is the deadlines.  What may be
concluded, from what evidence:

- **Finished** means: at rest (armctl/core/evidence.py; no SD program advancing, the estimate
  over), at the last frame's target, not paused in two agreeing reports, and the frames after
  the last motion (which leave no trace) finished even for an arm ``slowest_factor`` times
  slower than the model, counted from that motion's end (``rest_proves_all_written``).  The
  deadline is the queued motion × the slowest arm factor + a slack; an arm still visibly
  working past it is waited for (up to ``max(OVERRUN_MIN_S, the job)``) and the summary says
  so, and so is one still but not re-read in every kind yet (a slack after its last change) or
  with frames rest cannot prove still pending (a slack after their time bound), or at the last
  target before the frames after the last motion are past their time bound (counted from the
  last change seen, which a corrupted report after the arm stopped moves on); anything else
  ends "no confirmation" with the likeliest reason (``why_not_finished``).
- **Held mid-job** (the FIFO bound, or a control frame on arrival waiting for the frames
  before it, with only evidence to let the next frame go): the same proof — at rest, at the
  last target written, not paused, the trailing frames surely done — proves every frame
  written finished, and the job goes on: what time cannot confirm (an arc from an unverified
  joint end) never holds a job for ever.  Where a run of frames before the last move may hold
  the arm at that same target (``resting_before_last_move``), the rest proves the frames before
  the first such run (``rest_proves_done_before``) and time the rest.
- **An SD program held mid-job** (time never confirms a PROGRAM): its own part,
  armctl/core/job_program.py; a program no report showed running leaves the job only
  ``finished, unproven``.
- **The script's own PAUSE**: nothing is written behind it; once two agreeing reports read
  after it landed say the arm is paused, every frame written ran and the job ends PAUSED; an
  arm that does not report the pause in the time its queue takes ends "no confirmation".
- **A sign of loss** (``check_job_time``): the arm at rest at the last target sooner than the
  frames sent could take at the fastest plausible pace ends FRAMES_LOST.  FINISHED also needs
  a proven FIFO size or every frame confirmed by the arm's reports (``finished_outcome``):
  time alone cannot tell a frame run from a frame dropped; else UNPROVEN.
"""

from __future__ import annotations

from enum import StrEnum

from .evidence import REST_CHECK_S
from .job_program import ProgramWait
from .job_readings import changes_readings, landed_s, moves_arm, values_text
from .protocol import ArcStart, PauseToggle
from .streamer import ARRIVAL_SLACK_S, LOSS_SLACK_S, ROTATION_S

# Why a job whose frames only time (or a later frame's report) confirmed proves nothing on an
# arm whose FIFO size nobody measured; the resume of its log says it too (host/arm_worker.py)
FIFO_UNMEASURED = "the FIFO size is the document's, not measured on this arm: a frame it dropped would look the same"

# What an unproven finish says when measuring the arm would make it proof (``finished_outcome``)
PROBE_HINT = "run `armctl probe` once"

SETTLE_SLACK_S = 2.0  # beyond the estimate, how long to wait for the arm to come to rest
OVERRUN_MIN_S = 60.0  # the least time waited past the estimate for an arm still working


class Outcome(StrEnum):
    """How a job ended (a str, so the summary and the view print and compare it as text)."""

    RUNNING = "running"
    FINISHED = "finished"
    INTERRUPTED = "interrupted"
    FAILED = "failed"
    PORT_LOST = "port lost"
    NO_CONFIRMATION = "no confirmation"
    FRAMES_LOST = "frames may have been lost"
    UNPROVEN = "finished, unproven"
    PAUSED = "paused by the script"  # the script's own PAUSE paused the arm with lines still to run


def _after_last_frame(done_s: float, written, now: float) -> float:
    """The arm's rest at ``done_s`` (``Arrival.done_at``), never before the last frame written left
    the wire: moves of a few ms back and forth alias into still readings (X comes every 270 ms),
    which dated a 3.63 s job's rest at 3.38 s.  (The loss check keeps the readings' own time.)"""
    recent = written.recent
    return min(max(done_s, recent[-1].wire_end_s), now) if recent else done_s


class JobEnd:
    """The end of one job: its deadlines and the proofs that end it."""

    def __init__(self, view, streamer, arrival, fifo_proven: bool, control_frames_proven: bool = True) -> None:
        self.view = view
        self.streamer = streamer
        self.arrival = arrival
        self.readings = arrival.readings
        self.written = arrival.written
        self.fifo_proven = fifo_proven
        self.control_frames_proven = control_frames_proven
        self.deadline_s = 0.0
        self.overran = False
        self.script_pause_deadline_s: float | None = None  # held behind one: how long its pause is waited for
        self.program = ProgramWait(view, streamer, arrival, self.overrun_limit_s)  # armctl/core/job_program.py

    def settle_deadline(self, now: float) -> float:
        """How long the end is waited for: the motion queued at the slowest pace, and no earlier
        than the frames after the last motion can surely be done (a long run of delays leaves
        no trace: only time tells, and an arm twice slower needs twice theirs)."""
        streamer = self.streamer
        # (the queue's motion at the slowest pace, without each frame's handling: a wait, not a proof)
        return max(streamer.done_by_s(now, streamer.queued_seconds(now), frames=0), self.trailing_done_s()) + SETTLE_SLACK_S

    def restart(self, now: float) -> None:
        """The end is waited for from ``now`` (all written, aborted, or resumed from a pause)."""
        self.deadline_s = self.settle_deadline(now)

    def drain(self, now: float) -> Outcome | float:
        """Every frame written: the outcome once the arm's reports or the deadline end the job,
        else the time to wait until (``next_change_s``).  Finished means: at rest, at the last
        target, not paused, and the estimate agrees; anything else ends without claiming the
        job ran (frames cleared or dropped, a pause)."""
        view, readings = self.view, self.readings
        paused_at_end = self.paused_by_script()  # the script ends with its own PAUSE: every frame ran
        if paused_at_end:
            self.written.script_toggles[-1].seen = True
        if paused_at_end or self.rest_proves_all_written(now):
            # (the arm slower than the time bound allowed: a sign of loss) — motion after the
            # bound of every frame that may change the readings: a delay after them moves nothing
            moving_s = [sent.certain_end_s for sent in self.written.recent if changes_readings(sent)]
            if moving_s:
                self.streamer.moved_past_time_bound(self.readings.work_s, max(moving_s))
            self.streamer.confirm_all_done()
            view.arm_done_s = _after_last_frame(done_s := self.arrival.done_at(now), self.written, now)
            if paused_at_end:
                view.messages.append(f"the arm is paused, as the script's PAUSE at line "
                                     f"{self.written.script_pause_line()} leaves it")
            active_s = self.readings.active_s  # (blips left out: one read at the deadline proved nothing)
            if self.overran and active_s is not None and active_s > self.deadline_s - REST_CHECK_S:
                view.messages.append("the arm kept working past the estimate (moving, or running an SD program "
                                     "whose time armctl cannot know); armctl waited until it stopped")
            self.check_job_time(done_s)
            return self.finished_outcome()
        limit_s = self.deadline_s
        if now >= self.deadline_s:
            # Visibly working: the job is still running, whatever the estimate says; once it
            # stops, there is time to confirm it is where the job ends.
            active_s = readings.active_s
            active = active_s is not None and now - active_s < REST_CHECK_S
            self.overran = self.overran or active
            settle_until = [active_s + REST_CHECK_S + SETTLE_SLACK_S] if self.overran else []
            if readings.rest is not None and now - readings.rest_since_s() >= REST_CHECK_S > readings.rest_s():
                # Still for long enough, but some kind not re-read since (its reports lost): the
                # next reports may yet prove the rest — waited for as for an arm that just stopped.
                settle_until.append(readings.rest_since_s() + REST_CHECK_S + SETTLE_SLACK_S)
            if readings.rest is not None and (active_s is None or readings.rest[1] > active_s):
                # a change that is no visible work (a blip, armctl/core/job_readings.py; one yet to prove
                # one; pause, PWM, jitter) dates the rest proof: the proof it put off is waited for
                settle_until.append(readings.rest[1] + REST_CHECK_S + SETTLE_SLACK_S)
            resting = self.resting_before_last_move()
            if resting:  # frames rest cannot prove: their time bound (widened by a slow pace) decides
                settle_until.append(max(sent.certain_end_s for sent in resting) + SETTLE_SLACK_S)
            if self.arrival.at_last_target():
                # the frames after the last motion count from the last change seen, and one
                # corrupted report after the arm stopped is such a change: their time bound moved
                # past the deadline, and the rest that proves them is waited for
                settle_until.append(self.trailing_done_s() + SETTLE_SLACK_S)
            limit_s = min(self.deadline_s + self.overrun_limit_s(), max(settle_until, default=now))
            if now >= limit_s:
                return self.unconfirmed(self.why_not_finished())
        return self.next_change_s(now, limit_s)

    def unconfirmed(self, why: str) -> Outcome:
        """The job ends without the proof it waited for, saying ``why``."""
        self.view.messages.append(why)
        return Outcome.FRAMES_LOST if self.streamer.losses else Outcome.NO_CONFIRMATION

    def prove_held(self, now: float) -> Outcome | float | None:
        """Held mid-job (only evidence lets the next frame go): confirm what the arm's rest proves —
        an SD program at the head by its own proof (armctl/core/job_program.py), else the frames written
        (``rest_proves_done_before``), up to such a program.  The job's outcome when it ends here,
        a time to look again at (the program's limit), or None."""
        streamer = self.streamer
        head = streamer.pending[0]
        if streamer.program_time_unknown(head.command):
            answer = self.program.held(head, now)
            return self.unconfirmed(answer) if isinstance(answer, str) else answer
        before = self.rest_proves_done_before(now)
        if before is None:
            return None
        program = next((sent for sent in streamer.pending if streamer.program_time_unknown(sent.command)), None)
        if program is not None:
            before = min(before, program.index)  # the rest there says nothing of its program's end
        if before > head.index:
            streamer.confirm_all_done(now, before)  # (the time bound's chain restarts at now)
        return None

    def rest_proves_all_written(self, now: float) -> bool:
        """Every frame written has finished (``rest_proves_done_before`` leaves none unproven).
        The end of a job rests on it, and so does a job held mid-way (the FIFO bound, or rule
        (c), with only evidence to let the next frame go): it is what confirms an arc from an
        unverified joint end when no later frame's sighting can (armctl/core/streamer/time_bound.py
        ``allowance_s``: time cannot) — the arm has drained its FIFO by then, which costs
        the job that wait, never a frame."""
        return self.rest_proves_done_before(now) == self.streamer.sent

    def rest_proves_done_before(self, now: float) -> int | None:
        """The first frame the arm's rest at the last target (not paused, at rest since every
        frame written came: ``Readings.rest_since_s``) leaves unproven, or None when it proves
        nothing.  The frames after the last motion (a delay, M codes, PWM-only moves) leave no
        trace: an arm at rest at the last target says nothing about them, and an arm slower than
        the model would still be in them when the estimate runs out; they count as done once
        even an arm ``slowest_factor`` times slower has finished them (``trailing_done_s``) —
        then every frame written has run (``streamer.sent``).  And the arm rests as well in such
        a frame before the last motion, at readings the last target's may be (a wrist turning in
        place, a way back to the same point: ``resting_before_last_move``): then the arm is in
        such a run or past the last frame, so only the frames before the first of them have run
        (an arc that time cannot bound among them; held mid-job, the rest of them wait for the
        lower bound: the arm seen on a later frame's path, or their time bound)."""
        arrival = self.arrival
        if not (arrival.arm_at_rest(now) and arrival.at_last_target() and self.readings.paused is False):
            return None
        resting = self.resting_before_last_move()
        if resting:
            return resting[0].index
        return self.streamer.sent if now >= self.trailing_done_s() else None

    def resting_before_last_move(self) -> list:
        """The frames still pending before the last motion that move nothing (``moves_arm``), in
        runs between moves that could hold the arm still for ``REST_CHECK_S``: even an arm
        ``slowest_factor`` times slower, fed each frame at the line's pace, leaves a shorter run
        (a G54, an M code) before the rest check could see it still — and where the arm rests
        there may read as the last target in one of them (``Arrival.may_read_as_end_of``; a G54
        among them changes what the worktable X/Y/Z read) and the arm did not move since the frames
        before them finished (``Arrival.moved_past``): at rest far from it, the arm is plainly not done."""
        if (last := self.written.last_move) is None:
            return []
        streamer, resting, run, hold_s = self.streamer, [], [], ARRIVAL_SLACK_S
        target = self.written.recent[-1].segment  # what ``at_last_target`` compares the readings with
        may_read_as_end_of = self.arrival.may_read_as_end_of
        for sent in streamer.pending:
            if sent.index >= last.index or moves_arm(sent.segment) or isinstance(sent.command, ArcStart):
                if hold_s >= REST_CHECK_S and any(may_read_as_end_of(r.segment.end, target) for r in run) and not \
                        self.arrival.moved_past(run):
                    resting += run  # (a G300 runs with its G301: no rest in it)
                run, hold_s = [], ARRIVAL_SLACK_S
                if sent.index >= last.index:
                    break
                continue
            run.append(sent)
            hold_s = streamer.done_by_s(hold_s, sent.segment.duration_s) + streamer.frame_s
        return resting

    def trailing_done_s(self) -> float:
        motion = self.readings.motion
        motion_end_s = motion[1] if motion is not None else 0.0
        streamer = self.streamer
        # every frame after the last one that moves, however many (the recent ones are only the
        # last RECENT_FRAMES): their model time at the slowest pace, from the end of that motion …
        last = self.written.last_move
        moved_until_s = 0.0 if last is None else last.motion_before_s + last.segment.duration_s
        count = streamer.sent - (0 if last is None else last.index + 1)
        all_s = streamer.done_by_s(motion_end_s, streamer.motion_sent_s - moved_until_s, frames=count)
        # … and no earlier than the chain over the recent ones, each begun no earlier than it arrived
        trailing = []
        for sent in reversed(self.written.recent):
            if moves_arm(sent.segment):
                break
            trailing.append(sent)
        done_s = motion_end_s
        for sent in reversed(trailing):
            done_s = streamer.done_by_s(streamer.begun_by_s(sent.wire_end_s, done_s), sent.segment.duration_s)
        return max(done_s, all_s)

    def check_job_time(self, done_s: float) -> None:
        """A sign of loss: the arm at rest at the last target sooner than the motion of every
        frame written could take at the fastest plausible pace.  The arm time may be short by
        up to a rotation (the last motion seen is reported up to a rotation late), and a move from
        an unverified joint end may be any shorter than planned (``sure_motion_sent_s``)."""
        streamer = self.streamer
        streamer.check_time_bound()  # the other side: an arm slower than the time bound allows
        arm_s = done_s - self.view.started_s
        least_s = streamer.sure_motion_sent_s * streamer.fastest_factor
        if arm_s + ROTATION_S + LOSS_SLACK_S >= least_s:
            return
        streamer.loss_found(
            f"the arm was at rest at the last target {arm_s:.1f} s after the first frame, but the frames sent take "
            f"{streamer.sure_motion_sent_s:.1f} s of motion (at least {least_s:.1f} s on an arm "
            f"{1 / streamer.fastest_factor:g}x faster than the model): some were not run (dropped by a full FIFO?)",
            streamer.first_time_only_index or 0)

    def finished_outcome(self) -> Outcome:
        """FINISHED only when nothing says a frame was lost and the claim rests on proof."""
        streamer = self.streamer
        if streamer.losses:
            return Outcome.FRAMES_LOST
        unproven = self.program.unproven() + streamer.runs_unproven()
        probe = len(unproven)  # the reasons `armctl probe` answers come after these
        if not self.fifo_proven and (streamer.confirmed_by_time or streamer.confirmed_unseen):
            unproven.append(f"{_frames_not_seen(streamer)}, and {FIFO_UNMEASURED}")
        control_sent = self.written.control_sent
        if not self.control_frames_proven and control_sent:
            unproven.append(f"the job sent {control_sent} control {'frame' if control_sent == 1 else 'frames'} "
                            "(POSE, PROGRAM, G54 …), and how the arm takes them is the document's guess (queued), "
                            "not measured on this arm: one that acts on them as they land cuts short the move "
                            "before each, and rests at the last target all the same")
        if unproven:
            self.view.probe_answers = len(unproven) > probe
            hint = f"; {PROBE_HINT}" if self.view.probe_answers else ""
            self.view.messages.append(f"finished, unproven: {'; '.join(unproven)}{hint}")
            return Outcome.UNPROVEN
        return Outcome.FINISHED

    def overrun_limit_s(self) -> float:
        """How long past the deadline a visibly working arm is waited for: readings that
        jitter or are corrupted look like work, so the wait must end (an SD program longer
        than this ends "no confirmation")."""
        return max(OVERRUN_MIN_S, self.view.estimated_job_s)

    def why_not_finished(self) -> str:
        readings, recent = self.readings, self.written.recent
        if readings.paused:
            return "the arm reports it is paused: the rest of the job waits in its buffer"
        position = readings.position
        if readings.rest is not None and position is not None and recent and not self.arrival.at_last_target():
            named = self.arrival.arms_own_motion_last()
            if named is not None:
                return named
            return (f"the arm stopped at ({values_text(position)}) but the job's last target is "
                    f"({values_text(recent[-1].segment.end.xyz)}): "
                    "frames were lost, cleared or refused (a RESET CONNECTOR, a full buffer, a target out of the arm's reach?)")
        return "the arm did not confirm the end of the job in time (status frames missing?)"

    def next_change_s(self, now: float, limit_s: float) -> float:
        """The first time after ``now`` at which, with no new status frame, the answer could
        change: a rest or activity check maturing, the estimate running out, the deadline
        (``limit_s``, always after ``now``: a Wait never asks the host to wait for nothing)."""
        readings = self.readings
        times = [limit_s]
        if readings.rest is not None:
            times.append(readings.rest_since_s() + REST_CHECK_S)
        if readings.active_s is not None:
            times.append(readings.active_s + REST_CHECK_S)
        finish = self.streamer.estimated_finish_s()
        if finish is not None:
            times += (finish, self.trailing_done_s())
        return min((t for t in times if t > now), default=limit_s)

    # --- the script's own PAUSE ------------------------------------------------------------------

    def script_pause_holds(self, statement) -> bool:
        """The job's own PAUSE lines left the arm to pause (an odd number written) and the next
        statement does not resume it: nothing more is written.  On an arm whose control frames
        queue (H5) a frame behind the PAUSE would wait at the head of the paused FIFO, where no
        resume toggle could ever reach the head; on either arm the rest of the job waits for a
        resume nobody in this run can give (the run ends at the pause: ``held_by_script_pause``)."""
        return self.written.script_paused and not isinstance(statement.command, PauseToggle)

    def paused_by_script(self) -> bool:
        """The arm reports it is paused (two agreeing reports) in reports read after the job's last
        PAUSE landed: it acted — and, queued (H5), after every frame before it had run; on
        arrival, rule (c) wrote it only once they had."""
        written, readings = self.written, self.readings
        if not written.script_paused or readings.paused is not True or len(readings.pause_read_s) < 2:
            return False
        return readings.pause_read_s[0] >= landed_s(written.script_toggles[-1])

    def held_by_script_pause(self, now: float) -> Outcome | float:
        """Held behind the script's own PAUSE: once the arm reports the pause, every frame written
        ran, and the run ends "paused by the script" with the resume line after the PAUSE (the
        resume's start-up un-pauses the arm with its one toggle, its FIFO empty).  An arm that
        does not report the pause in the time its queue takes ends "no confirmation".  Else the
        time to wait until."""
        line = self.written.script_pause_line()
        if self.paused_by_script():
            self.written.script_toggles[-1].seen = True  # the arm's pause report: it ran
            self.streamer.confirm_all_done()
            following = getattr(self.view.next_statement, "line", None)
            self.view.messages.append(
                f"paused by the script's PAUSE at line {line}: the arm is paused, and the rest "
                f"of the job (from line {following}) was not sent; the printed resume un-pauses the arm and runs it")
            return Outcome.PAUSED
        if self.script_pause_deadline_s is None:
            self.script_pause_deadline_s = self.settle_deadline(now)
        if now >= self.script_pause_deadline_s:
            self.view.messages.append(f"the arm did not report the pause of the script's PAUSE at line "
                                      f"{line} in time: the rest of the job was not sent")
            return Outcome.FRAMES_LOST if self.streamer.losses else Outcome.NO_CONFIRMATION
        return self.script_pause_deadline_s


def _frames_not_seen(streamer) -> str:
    """The frames the arm's reports did not see run, as the summary says it."""
    parts = []
    if streamer.confirmed_by_time:
        count = streamer.confirmed_by_time
        parts.append(f"{count} {'frame was' if count == 1 else 'frames were'} confirmed by time alone")
    if streamer.confirmed_unseen:
        parts.append(f"{streamer.confirmed_unseen} only by a report on a later frame (gone from the FIFO, "
                     "never seen running)")
    return " and ".join(parts)
