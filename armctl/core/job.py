"""The job engine: when is a streamed job over, how does it stop, and what can be said about it?

Strategy: pure, sans-I/O (after h11 and armctl/jog/session.py) — status frames, write
completions and ``now`` come in as arguments; the next thing to do comes out.  A host (``armctl
run``'s runner over a port, the benchmark's harness over a simulated arm, the Python API) loops:

    feed every status frame read: ``receive_status(frame, now)``
    ask ``next_action(now)``:
        ``Write(frame, statement)`` → write the frame, then ``wrote(now)``
        ``Wait(until_s)``           → wait until ``until_s`` or the next status frame (None: the frame)
        ``Done(outcome)``           → stop; ``view`` says what ran and where to resume

so the rules that end a job live here once, whoever drives it, and a virtual-time host can jump
straight to the next event: nothing here changes between status frames except at the times a
``Wait`` names.

``Job`` is the façade; each part owns its state and says in its docstring what it may conclude
from what evidence:

- armctl/core/evidence.py — the rules of arm evidence: two agreeing reports, at rest.
- armctl/core/job_readings.py — the record: the arm's readings (at rest, paused, active) and the
  frames written.
- armctl/core/job_arrival.py — where the arm rests against the frames written: what ran, the
  resume line, an arm whose control frames act as they land.
- armctl/core/job_end.py — when the job is over and how it ended (``Outcome``): finished, held
  mid-job, the script's own PAUSE, the signs of loss.
- armctl/core/job_stop.py — stopping: the abort sequence, the settling after it, what a resume sends.
- armctl/core/job_control.py — pause, resume and the feed override of a running job.

Rules of the façade:
- Streaming: the pacing strategy (the ``Streamer`` by default; the benchmark's baselines answer
  the same ``receive_status / next_write_time / wrote``) says when the next frame may go.  The
  streamer also watches every write and frame when another strategy paces, so what is known
  executed, the resume line and the end of the job are judged the same way for every strategy.
  Held (only evidence lets the next frame go), the rest that proves the frames written finished
  (armctl/core/job_end.py) lets it go, and a status frame that may complete that rest is news to a
  virtual-time host.
- Stopping (``request_stop``: Ctrl-C, a failure the host met): nothing more of the job is
  written; the abort sequence goes instead — minus a pause toggle to an arm that reports it
  is paused, which would resume it — then the engine waits for the arm to come to rest and
  ends INTERRUPTED (or FAILED, with the reason among the messages).  The control mode shapes
  the sequence and the start of the next run (``abort_frames``, ``resume_frames``), so an abort
  and its resume line run every line once.  Before the first frame there is nothing to stop:
  no abort sequence, the job ends at once (``Stop.begin``).
- Paused means two agreeing pause reports (``agreed_pause``, armctl/core/evidence.py): one corrupted
  byte must never make armctl toggle the arm.  ``armctl run``'s start-up check uses the same rule.
- The resume line is the first statement not known finished (an arc's G301 resumes at its G300).
- News (``receive_status``'s answer): a status frame is news when it may change what
  ``next_action`` answers.  It cannot, while streaming: a kind the engine only counts
  (worktable, wrist, SD file length and status), a pause report that changes no control state,
  a position or joints report that moved neither the lower bound nor the streamer's plan
  (``Streamer.plan_changes``: on the same frame's path where the estimate has the arm), or an
  SD run position that did not move, with nothing newly known consumed and no pause asked or
  in force (and, while only evidence lets the next frame go, no rest that may now prove every
  frame written finished) — a virtual-time host reads on past it without asking (``Wait``'s
  promise: nothing changes between status frames but at its time).  Past streaming every frame
  is news: the end-of-job checks compare times their own way (``now - since >= REST_CHECK_S``),
  which may hold a rounding error before the time the Wait named; a frame read then must find
  them as it always did.  Draining, one answer holds until the estimate runs out or the
  deadline (``JobEnd.drain``: no rest before the estimated finish, nothing else before the
  deadline): a frame read before both that moved neither the estimate nor the bound may change
  only the time of a Wait, never to before either (the host is woken by then, or by a later frame).
- Control of a running job (``pause``, ``resume``, ``set_feed_override``; the state machine is
  armctl/core/job_control.py): a pause toggle asked for goes as soon as the wire is free, never held
  behind the streamer's capacity or lead; nothing of the job is written while a pause is asked
  or in force, and the end of the job waits for it.  The feed override is applied to the
  statement about to be written, and the streamer plans that very command, so the lead and the
  estimate follow it.  A stop sends its pause toggle only when the arm would otherwise run on.
- A summary claims only what evidence proves.  Each frame counts as confirmed by the arm's
  reports, by time alone, or as gone from the FIFO without a proof that it ran
  (``RunView.frames_by_reports`` / ``frames_by_time`` / ``frames_unseen``: armctl/core/streamer/ledger.py).  Any sign of loss
  — the streamer saw the arm skip frames (``Streamer.losses``), or the arm at rest at the end
  sooner than the frames sent could take at the fastest plausible pace — ends FRAMES_LOST with
  the evidence, and nothing from the first frame that may be lost on is claimed executed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Iterable, Iterator

from .evidence import REST_CHECK_S, known_still_s  # noqa: F401  (re-exported: the rule of rest)
from .job_arrival import Arrival
from .job_control import JobControl, agreed_pause, control_frames_of  # noqa: F401  (agreed_pause: the pause rule, re-exported)
from .job_end import OVERRUN_MIN_S, SETTLE_SLACK_S, JobEnd, Outcome  # noqa: F401  (re-exported)
from .job_readings import (  # noqa: F401  (re-exported: the tolerances and the jitter test)
    PAUSE_KIND, RECENT_FRAMES, REST_VALUES, RUN_POSITION_KIND, TARGET_DEG, TARGET_MM, Readings, Written,
    moved_clearly as _moved_clearly, moves_arm as _moves_arm, slot_moved as _slot_moved,
)
from .job_stop import ABORT_SEQUENCES, Stop, abort_frames, resume_frames  # noqa: F401  (re-exported)
from .protocol import PauseToggle, StatusFrame


class _Phase(Enum):
    START = "start"
    STREAMING = "streaming"  # frames of the job still to write
    DRAINING = "draining"  # every frame written: waiting for the arm to finish
    ABORTING = "aborting"  # writing the abort sequence
    SETTLING = "settling"  # waiting for the arm to come to rest after the abort
    DONE = "done"


# The host's actions: the one vocabulary of the host driver (armctl/core/actions.py), imported here
# where they were defined (``from armctl.core.job import Write, Wait, Done`` keeps working).
from .actions import Done, Wait, Write  # noqa: E402,F401


@dataclass
class RunView:
    """What the run knows, for the panel, the plain progress lines and the summary."""

    total_frames: int
    estimated_job_s: float
    lead_s: float
    capacity: int
    total_lines: int = 0
    started_s: float = 0.0
    now_s: float = 0.0
    frames_sent: int = 0
    last_sent: object = None  # the Statement of the last frame written
    last_done: object = None  # the Statement of the last frame known finished
    next_statement: object = None  # the first Statement not written
    queued_frames_bound: int = 0
    queued_s: float = 0.0
    remaining_motion_s: float = 0.0
    frame_s: float = 0.0  # one frame's time on the line (``protocol.frame_seconds`` of the baud rate)
    position_mm: tuple | None = None
    status_frames: int = 0
    arm_done_s: float | None = None  # when the arm came to rest at the end (model time)
    outcome: str = Outcome.RUNNING  # an Outcome
    frames_by_reports: int = 0  # frames confirmed by the arm's reports (position, joints, at rest at the end)
    frames_by_time: int = 0  # frames confirmed only by time (the slowest-arm bound)
    frames_unseen: int = 0  # frames a report proves gone from the FIFO (a later frame's sighting), never seen running
    messages: list = field(default_factory=list)
    pause_state: str = "running"  # armctl/core/job_control.py's PauseState: running, pausing, paused, resuming
    pause_label: str = "running"  # what the panel shows (the arm's reports decide it)
    feed_percent: int = 100  # the feed override of the frames written from now on
    feed_clamped: bool = False  # the last frame scaled was held to the profile's speed limit
    probe_answers: bool = False  # "finished, unproven" rests on settings `armctl probe` measures (PROBE_HINT)

    @property
    def elapsed_s(self) -> float:
        return self.now_s - self.started_s

    @property
    def eta_s(self) -> float:
        """Seconds until the arm should be done: what is queued, then what is still unsent (at
        the feed override: motion time taken as inverse to speed, ramps aside) — never less than
        the unsent frames' time on the line, which a line-bound job waits for (301 moves of 4 ms
        take 15.1 s at 9600 baud, their motion 3.2 s)."""
        unsent_s = max(0, self.total_frames - self.frames_sent) * self.frame_s
        return max(self.queued_s + self.remaining_motion_s * 100 / self.feed_percent, unsent_s)

    first_not_done: object = None  # the Statement to resume at: the first not known finished

    @property
    def frames_known_done(self) -> int:
        """Frames the streamer knows finished (its lower bound): the ones written and not queued."""
        return max(0, self.frames_sent - self.queued_frames_bound)

    def resume_line(self) -> int | None:
        """The line ``--from-line`` should name to continue after the last line known executed."""
        return None if self.first_not_done is None else self.first_not_done.line

    @property
    def arm_time_s(self) -> float | None:
        """From the first frame to the arm at rest at the end (None unless the job finished)."""
        return None if self.arm_done_s is None else self.arm_done_s - self.started_s


class Job:
    """One job: ``statements`` (objects with ``command`` and ``line``) paced by ``pacing``,
    judged by ``streamer``; see the module docstring."""

    def __init__(self, streamer, statements: Iterable, view: RunView, *, pacing=None,
                 abort_sequence: tuple = ABORT_SEQUENCES["pause"], control_frames: str | None = None,
                 fifo_proven: bool = True, control_frames_proven: bool = True) -> None:
        """``fifo_proven``, ``control_frames_proven``: the connector is known to hold the profile's
        ``fifo_frames``, to take control frames as it says (``armctl.host.link`` decides both)."""
        self.streamer = streamer
        self.fifo_proven = fifo_proven
        streamer.fifo_holds_all = fifo_proven  # else a frame gone from the FIFO may have been dropped, not run
        # pause, resume and the feed override (armctl/core/job_control.py), under the profile the
        # streamer plans with: its speed limits (never passed) and its control-frame mode (H5)
        profile = streamer.planner.model.profile
        self.control = JobControl(profile.speed, control_frames or control_frames_of(profile))
        self.pacing = streamer if pacing is None else pacing
        self.statements: Iterator = iter(statements)
        self.view = view
        self.abort_sequence = tuple(abort_sequence)
        self.phase = _Phase.START
        self.stop_requested = False
        self.failure: str | None = None  # why the job stops, when not by Ctrl-C
        self.outcome: Outcome | None = None
        self.written = Written(streamer.reports_robot_xyz)  # the record (armctl/core/job_readings.py): the frames written ...
        self.readings = Readings(self.written)  # ... and the arm's reports
        self.arrival = Arrival(self.readings, self.written, streamer)  # armctl/core/job_arrival.py
        self.end = JobEnd(view, streamer, self.arrival, fifo_proven, control_frames_proven)  # armctl/core/job_end.py
        self.stop = Stop(view, self.control, self.end)  # armctl/core/job_stop.py: the abort and the settling
        self._write: Write | None = None  # the Write asked for and not yet done
        self._command = None  # the command that Write carries (the feed override applied)
        self._control_version = 0  # the control state the view shows
        # the view is current at this time: ``wrote`` refreshed it and nothing was taken or asked
        # since (``next_action`` at that time would refresh it to the same values: it skips that)
        self._fresh_s: float | None = None
        self._held = False  # streaming, and only evidence lets the next frame go (``JobEnd.rest_proves_all_written``)

    # --- input ------------------------------------------------------------------------------

    def receive_status(self, frame: StatusFrame, now: float) -> bool:
        """Take one status frame read at ``now``.  True when it may change what ``next_action``
        answers (see "News" in the module docstring); ``receive_statuses`` of one frame."""
        return self.receive_statuses((frame,), (now,)) is not None

    def receive_statuses(self, frames, times) -> int | None:
        """``receive_status`` for each frame of ``frames`` read at the time of ``times`` at the same
        place, in order, up to the first that is news: its place (the frames after it are not
        taken), or None when none was (all taken).  A virtual wait's news receiver
        (``JobRunner.take_statuses``) hands over a quiet stretch this way: one call, not one a frame."""
        self._fresh_s = None
        streamer, view, control, readings = self.streamer, self.view, self.control, self.readings
        streamer_receive, take = streamer.receive_status, readings.take
        other = self.pacing if self.pacing is not streamer else None
        streaming = self.phase is _Phase.STREAMING
        draining = self.phase is _Phase.DRAINING
        held = self._held and streaming
        deadline_s = self.end.deadline_s
        rest_values = REST_VALUES
        k = -1
        for frame in frames:
            k += 1
            now = times[k]
            consumed, plan = streamer.consumed_lower_bound, streamer.plan_changes
            streamer_receive(frame, now)
            if streamer.consumed_lower_bound != consumed:
                self.written.done(streamer.consumed_lower_bound, now)  # (what a blip's reading may be explained by)
            # (see "News" in the module docstring: past streaming every frame is news; draining, ...)
            news = control.busy or (not streaming and not (
                draining and streamer.plan_changes == plan and now < deadline_s
                and now < (streamer.estimated_finish_s() or now)))
            if other is not None:
                other.receive_status(frame, now)
                news = True  # another strategy may act on any frame
            kind = frame.KIND
            values_of = rest_values.get(kind)
            if values_of is None:
                if kind == RUN_POSITION_KIND and readings.take_run_position(frame.value, now):
                    news = True  # an SD program advancing, even with the arm standing still
                if news or streamer.consumed_lower_bound != consumed:
                    view.status_frames += k + 1
                    return k
                continue
            values = values_of(frame)
            if kind == PAUSE_KIND:  # news while streaming only through the control state (or the bound)
                version = control.version
                control.observe(readings.take_pause(frame.paused, now))  # pausing… → paused, resuming… → running
                news = news or control.version != version
            else:  # position and joints while streaming: news only through the streamer's
                # evidence (the bound, below) or its plan (the estimate's end times, the pace)
                news = news or streamer.plan_changes != plan
                if kind == 0:
                    view.position_mm = values = streamer.worktable_xyz(values)  # status_xyz_frame
            if not take(kind, values, now) and held and now - readings.rest_since_s() >= REST_CHECK_S:
                news = True  # the rest that may prove every frame written finished (``JobEnd.rest_proves_all_written``)
            if news or streamer.consumed_lower_bound != consumed:
                view.status_frames += k + 1
                return k
        view.status_frames += k + 1  # (counted once: nothing above reads it)
        return None

    def wrote(self, now: float) -> None:
        """The host wrote the frame the last ``Write`` asked for, starting at ``now``."""
        write, self._write = self._write, None
        streamer = self.streamer
        if self.phase is _Phase.ABORTING:
            return self.stop.wrote()
        if write is not None and write.control is not None:  # a pause toggle the user asked for
            self.control.take_toggle()
            streamer.wrote_control(now)
            self._refresh(now)
            return
        view = self.view
        statement = view.next_statement
        command = self._command
        sent = streamer.wrote(command, now, tag=statement)
        if self.pacing is not streamer:
            self.pacing.wrote(command, now, statement)
        self.written.note(sent)
        view.frames_sent += 1
        view.last_sent = statement
        view.next_statement = next(self.statements, None)
        # the estimate's remaining motion is at 100 %: the frame's own time, unscaled
        view.remaining_motion_s = max(0.0, view.remaining_motion_s - sent.segment.duration_s * self.control.feed.percent / 100)
        self._refresh(now)
        self._fresh_s = now

    def request_stop(self, why: str | None = None) -> None:
        """Stop at the next action: the abort sequence, then wait for rest.  ``why`` (a failure
        the host met, e.g. a --log that cannot be written) makes the outcome FAILED."""
        self.failure = self.failure or why
        self.stop_requested, self._fresh_s = True, None

    def pause(self) -> bool:
        """Pause the job: a pause toggle, and nothing more written until ``resume`` (False when
        already pausing or paused, the arm reports it is paused, or the job is stopping; not behind
        the script's own PAUSE: a second toggle would undo it, or, queued, resume the arm it paused)."""
        self._fresh_s = None
        return self._controllable and not self.written.script_paused and self.control.pause()

    def resume(self) -> bool:
        """Resume a pause asked with ``pause``: the toggle goes first, then the job's frames."""
        self._fresh_s = None
        return self._controllable and self.control.resume()

    @property
    def _controllable(self) -> bool:
        """Pause and resume act while the job streams or drains; a stop has its own sequence."""
        return not self.stop_requested and self.phase in (_Phase.START, _Phase.STREAMING, _Phase.DRAINING)

    def set_feed_override(self, percent: int) -> int:
        """Rescale the speed of the frames not yet written (10…200 %, 10 % steps); returns the
        percentage in force."""
        self._fresh_s = None
        return self.control.set_feed_override(percent)

    def port_lost(self, why: str | None = None) -> None:
        """The port went away: nothing more can be written or read."""
        if why:
            self.view.messages.append(why)
        self._finish(Outcome.PORT_LOST, self.view.now_s)

    # --- output -----------------------------------------------------------------------------

    def next_action(self, now: float) -> Write | Wait | Done:
        """What the host does next; asking again without news gives the same answer."""
        if self.outcome is not None:
            return Done(self.outcome)
        phase = self.phase
        if phase is _Phase.START:
            self.view.started_s = now
            self.view.next_statement = next(self.statements, None)
            phase = self.phase = _Phase.STREAMING
        if self.stop_requested and phase in (_Phase.STREAMING, _Phase.DRAINING):
            self._begin_abort()
            phase = self.phase
        fresh, self._fresh_s = self._fresh_s, None
        control, view = self.control, self.view
        statement = view.next_statement
        # The view follows the engine at ``now`` before anything is decided — except where only
        # the pacing decides (streaming, no control in hand, the feed's command for ``statement``
        # planned already: ``command_for`` changes nothing a view shows): there it follows once
        # the answer is known, and not at all for a Write, which ``wrote`` refreshes at this time
        # before anyone reads the view (a write that fails: ``port_lost`` refreshes at ``now_s``).
        deferred = fresh != now and phase is _Phase.STREAMING and not control.busy and statement is not None \
            and not self.written.script_paused and control.planned_for(statement)
        if deferred:
            view.now_s = now
        elif fresh != now:  # (else ``wrote`` refreshed the view at this time, and nothing changed since)
            self._refresh(now)
        if control.busy and phase in (_Phase.STREAMING, _Phase.DRAINING):
            held = _control_action(self, now)
            if held is not None:
                return held
        if phase is _Phase.STREAMING:
            if statement is not None:  # written when the pacing lets it go, else the time it may
                if self.written.script_paused and self.end.script_pause_holds(statement):
                    return self._ended_or_wait(self.end.held_by_script_pause(now), now)
                command = control.command_for(statement)
                pacing, streamer = self.pacing, self.streamer
                when = pacing.next_write_time(now, command)
                self._held = when is None and pacing is streamer
                look_s = None  # held: when to look again without news (an SD program's limit)
                if self._held and streamer.pending:
                    if deferred:  # (before the rest is judged and confirms frames)
                        self._refresh(now)
                        deferred = False
                    consumed = streamer.consumed_lower_bound
                    look_s = self.end.prove_held(now)
                    if isinstance(look_s, Outcome):
                        return self._finish(look_s, now)
                    if streamer.consumed_lower_bound != consumed:
                        when = pacing.next_write_time(now, command)
                if when is not None and when <= now:
                    if self._write is None:
                        self._write, self._command = Write(command.encode(), statement), command
                    return self._write
                if deferred:
                    self._refresh(now)
                return Wait(look_s if when is None else when)
            self.phase = _Phase.DRAINING
            self.end.restart(now)
            return self._ended_or_wait(self.end.drain(now), now)
        if phase is _Phase.DRAINING:
            return self._ended_or_wait(self.end.drain(now), now)
        if phase is _Phase.ABORTING:
            if self.stop.frames:
                if self._write is None:
                    self._write = Write(self.stop.frames[0].encode(), None)
                return self._write
            self.phase = _Phase.SETTLING
            self.end.restart(now)
        return self._settling(now)

    def _ended_or_wait(self, answer: Outcome | float, now: float) -> Wait | Done:
        """A part's answer (armctl/core/job_end.py): how the job ended, or the time to wait until."""
        return self._finish(answer, now) if isinstance(answer, Outcome) else Wait(answer)

    @property
    def streaming(self) -> bool:
        """Frames of the job are still to be written (the pacing strategy's answers are current)."""
        return self.phase is _Phase.STREAMING

    @property
    def aborting(self) -> bool:
        """Frames of the abort sequence are being written (a write that fails now did not stop the arm)."""
        return self.phase is _Phase.ABORTING

    # --- the end ----------------------------------------------------------------------------

    def _settling(self, now: float) -> Wait | Done:
        """After the abort sequence: until the arm is at rest or the deadline (``Stop.settle``)."""
        answer = self.stop.settle(now, self.failure)
        if answer is None:  # a RESET CONNECTOR to clear what is still queued goes first
            self.phase = _Phase.ABORTING
            return self.next_action(now)
        return self._ended_or_wait(answer, now)

    def _finish(self, outcome: Outcome, now: float) -> Done:
        view = self.view
        if outcome in (Outcome.FAILED,) and self.failure:
            view.messages.append(self.failure)
        view.messages.extend(self.streamer.losses)
        self.outcome = outcome
        self.phase = _Phase.DONE
        view.outcome = outcome
        self._refresh(now)
        return Done(outcome)

    def _begin_abort(self) -> None:
        """Nothing more of the job is written; the abort sequence goes instead (``Stop.begin``)."""
        self.stop.begin(self.abort_sequence)
        self._write = None
        self.phase = _Phase.ABORTING

    @property
    def arm_paused(self) -> bool | None:
        """The pause state when the last two pause reports agree (armctl/core/evidence.py ``agreed``)."""
        return self.readings.paused

    # --- the view ---------------------------------------------------------------------------

    def _refresh(self, now: float) -> None:
        """The view follows the engine at ``now``."""
        view, streamer, control = self.view, self.streamer, self.control
        view.now_s = now
        view.queued_frames_bound = streamer.frames_in_flight_bound
        view.queued_s = streamer.queued_seconds(now)
        view.last_done = streamer.last_known_done()
        view.first_not_done = self.arrival.first_not_done(view)
        if control.version != self._control_version:  # the view follows only a change (it follows the pause reports)
            self._control_version = control.version
            view.pause_state, view.pause_label = control.state.value, control.label
            view.feed_percent, view.feed_clamped = control.feed.percent, control.feed.clamped
        view.frames_by_reports, view.frames_by_time = streamer.confirmed_by_reports, streamer.confirmed_by_time
        view.frames_unseen = streamer.confirmed_unseen
        suspect = streamer.first_suspect_index
        if suspect is not None and suspect < streamer.consumed_lower_bound:
            # nothing from the first frame that may have been lost on is claimed executed
            view.last_done = streamer.tag_of(suspect - 1) if suspect > 0 else None
            view.first_not_done = streamer.tag_of(suspect) or view.first_not_done


def _control_action(job: Job, now: float) -> Write | Wait | None:
    """A pause toggle the user asked for goes as soon as the wire is free — never behind the
    streamer's capacity or lead, so a resume is not held behind a FIFO it counts as full;
    while a pause is asked or in force nothing else is written, and the end of the job
    waits (its deadline starts again from the resume).  None: carry on.  (``Job.next_action``'s
    own step, outside the class: it runs only while a pause or resume is in hand.)"""
    control = job.control
    if control.toggle_due:
        if job._write is not None and job._write.statement is not None:
            job._write = None  # a frame asked for and not written yet: the toggle goes first
        wire_s = job.streamer.wire_free_s
        if wire_s > now:
            return Wait(wire_s)
        if job._write is None:
            job._write = Write(PauseToggle().encode(), None, "pause toggle")
        return job._write
    if control.holds_feed:
        if job.phase is _Phase.DRAINING:
            job.end.restart(now)
        job.end.program.held_by_pause_s = now  # an SD program's wait starts again from the resume
        return Wait(None)  # until the arm reports (pausing → paused) or the user resumes
    return None
