"""The job engine: when is a streamed job over, how does it stop, and what can be said about it?

Strategy: pure, sans-I/O (after h11 and armctl/jog/session.py) — status frames, write
completions and ``now`` come in as arguments; the next thing to do comes out.  A host (``armctl
run``'s runner over a port, the benchmark's harness over a simulated arm, the Python API) loops:

    feed every status frame read: ``receive_status(frame, now)``
    ask ``next_action(now)``:
        ``Write(frame, statement)`` → write the frame, then ``wrote(now)``
        ``Wait(until_s)``           → wait until ``until_s`` or the next status frame (None: the frame)
        ``Finished(outcome)``       → stop; ``view`` says what ran and where to resume

so the rules that end a job live here once, whoever drives it, and a virtual-time host can jump
straight to the next event: nothing here changes between status frames except at the times a
``Wait`` names.

Rules:
- Streaming: the pacing strategy (the ``Streamer`` by default; the benchmark's baselines answer
  the same ``receive_status / next_write_time / wrote``) says when the next frame may go.  The
  streamer also watches every write and frame when another strategy paces, so what is known
  executed, the resume line and the end of the job are judged the same way for every strategy.
- Finished means: at rest (the position, joints and PWM unchanged for ``REST_CHECK_S``, each
  kind re-read in that time: a lost report is no reading, ``_rest_s``; no SD program
  advancing, the estimate over), at the last frame's target, not paused in two agreeing
  reports, and the frames after the last motion (which leave no trace) finished even
  for an arm ``slowest_factor`` times slower than the model, counted from that motion's end.  The deadline is the queued motion × the slowest arm factor + a slack; an
  arm still visibly working past it is waited for (up to ``max(OVERRUN_MIN_S, the job)``) and
  the summary says so, and so is one still but not re-read in every kind yet (a slack after its
  last change) or with frames rest cannot prove still pending (a slack after their time bound);
  anything else ends "no confirmation" with the likeliest reason.
- Held mid-job (the FIFO bound, or a control frame on arrival waiting for the frames before it,
  with only evidence to let the next frame go): the same proof — at rest, at the last target
  written, not paused, the trailing frames surely done — proves every frame written finished,
  and the job goes on (``_rest_proves_all_written``): what time cannot confirm (an arc from an
  unverified joint end) never holds a job for ever.  Where a run of frames before the last move
  may hold the arm at that same target, the rest proves the frames before the first such run
  (``_rest_proves_done_before``) and time the rest.  A status frame that may complete that
  rest is news to a virtual-time host.
- Stopping (``request_stop``: Ctrl-C, a failure the host met): nothing more of the job is
  written; the abort sequence goes instead — minus a pause toggle to an arm that reports it
  is paused, which would resume it — then the engine waits for the arm to come to rest and
  ends INTERRUPTED (or FAILED, with the reason among the messages).  The control mode shapes
  the sequence and the start of the next run (``abort_frames``, ``resume_frames``), so an abort
  and its resume line run every line once.
- Paused means two agreeing pause reports (``agreed_pause``): one corrupted byte must never make
  armctl toggle the arm.  ``armctl run``'s start-up check uses the same rule.
- The resume line is the first statement not known finished (an arc's G301 resumes at its G300).
- Control of a running job (``pause``, ``resume``, ``set_feed_override``; the state machine is
  armctl/job_control.py): a pause toggle asked for goes as soon as the wire is free, never held
  behind the streamer's capacity or lead; nothing of the job is written while a pause is asked
  or in force, and the end of the job waits for it.  The feed override is applied to the
  statement about to be written, and the streamer plans that very command, so the lead and the
  estimate follow it.  A stop sends its pause toggle only when the arm would otherwise run on.
- A summary claims only what evidence proves.  Each frame counts as confirmed by the arm's
  reports, by time alone, or as gone from the FIFO without a proof that it ran
  (``RunView.frames_by_reports`` / ``frames_by_time`` / ``frames_unseen``: armctl/streamer.py).  Any sign of loss
  — the streamer saw the arm skip frames (``Streamer.losses``), or the arm at rest at the end
  sooner than the frames sent could take at the fastest plausible pace — ends FRAMES_LOST with
  the evidence, and nothing from the first frame that may be lost on is claimed executed.
  ``done`` (FINISHED) also needs a proven FIFO size (``fifo_proven``: probed, or a simulator
  known to hold at least the profile's) or every frame confirmed by the arm's reports: time
  alone cannot tell a frame run from a frame dropped (nor can a report on a later frame); else
  the job ends UNPROVEN.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field, fields
from enum import Enum, StrEnum
from operator import attrgetter
from typing import Iterable, Iterator

from .job_control import JobControl, agreed_pause, control_frames_of  # noqa: F401  (agreed_pause: the pause rule, re-exported)
from .streamer import LOSS_SLACK_S, ROTATION_S
from .protocol import (
    CONTROL_COMMANDS, ArcEnd, ArcStart, GoToPose, JointsHighStatus, JointsLowStatus, PauseStatus, PauseToggle, PositionStatus,
    ResetConnector, RunPositionStatus, RunProgram, StatusFrame,
)
from .streamer import ARRIVAL_SLACK_S
from .motion import distance_to_path

ABORT_SEQUENCES = {
    "pause": (PauseToggle(),),  # H5: takes effect after the frames already queued
    "reset-connector": (ResetConnector(),),  # clears the FIFO when it acts (queued frames are lost)
    "none": (),
}


def abort_frames(name: str, control_on_arrival: bool) -> tuple:
    """The frames of the abort sequence ``name`` for an arm whose control frames act as they land
    (``control_frames = "arrival"``) or queue (H5).  On arrival a pause freezes the move in
    progress and leaves the queue behind it intact: a RESET CONNECTOR follows (it acts as it lands
    too), so nothing the run wrote is left waiting for a later resume to start unannounced, and
    the resume line is right for the arm as it is (see ``resume_frames``)."""
    frames = ABORT_SEQUENCES[name]
    if control_on_arrival and name == "pause":
        frames += (ResetConnector(),)
    return frames


def resume_frames(control_on_arrival: bool) -> tuple:
    """What a run sends to an arm found paused (two agreeing reports), before anything else.
    Queued (H5): one pause toggle — the pause acted at the head of the FIFO, so nothing of the
    job waits behind it, and a RESET CONNECTOR would wait at the head of a paused arm forever.
    On arrival: RESET CONNECTOR first (whatever is still queued — left by another program or an
    older armctl — is cleared, not run a second time), then the toggle: the frozen move finishes,
    and the run re-sends its line, an absolute move to where the arm then is (idempotent)."""
    return (ResetConnector(), PauseToggle()) if control_on_arrival else (PauseToggle(),)


REST_CHECK_S = 0.6  # the arm counts as at rest when it reported the same pose this long
SETTLE_SLACK_S = 2.0  # beyond the estimate, how long to wait for the arm to come to rest
OVERRUN_MIN_S = 60.0  # the least time waited past the estimate for an arm still working
TARGET_MM = 0.5  # how close the reported position must be to the last target (0.1 mm resolution)
TARGET_DEG = 0.2
# The kinds whose readings say whether the arm is at rest — position, joints 1-3, joints 4-6,
# pause and PWM — and their fields, read directly (this runs for every status frame).
_REST_VALUES = {cls.KIND: attrgetter(*(f.name for f in fields(cls)))
                for cls in (PositionStatus, JointsLowStatus, JointsHighStatus, PauseStatus)}
_RUN_POSITION_KIND = RunPositionStatus.KIND
RECENT_FRAMES = 64  # frames written kept for the end of the job (the trailing frames that move nothing)


def known_still_s(changed_s: float, read_s: Iterable[float]) -> float:
    """How long readings are known unchanged: from their last change seen (``changed_s``) to the
    oldest of each kind's latest report (``read_s``) — not to now: a kind whose reports were lost
    or corrupted since says nothing about that time (a wrist turning while the joints 4-6 reports
    are lost looks still to every other kind).  The one test of rest (``Job``, ``wait_for_rest``)."""
    return min(read_s) - changed_s


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


# The host's actions: the one vocabulary of the host driver (armctl/actions.py), imported here
# where they were defined (``from armctl.job import Write, Wait, Finished`` keeps working).
from .actions import Done, Finished, Wait, Write  # noqa: E402,F401


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
    position_mm: tuple | None = None
    status_frames: int = 0
    arm_done_s: float | None = None  # when the arm came to rest at the end (model time)
    outcome: str = Outcome.RUNNING  # an Outcome
    frames_by_reports: int = 0  # frames confirmed by the arm's reports (position, joints, at rest at the end)
    frames_by_time: int = 0  # frames confirmed only by time (the slowest-arm bound)
    frames_unseen: int = 0  # frames a report proves gone from the FIFO (a later frame's sighting), never seen running
    messages: list = field(default_factory=list)
    pause_state: str = "running"  # armctl/job_control.py's PauseState: running, pausing, paused, resuming
    pause_label: str = "running"  # what the panel shows (the arm's reports decide it)
    feed_percent: int = 100  # the feed override of the frames written from now on
    feed_clamped: bool = False  # the last frame scaled was held to the profile's speed limit

    @property
    def elapsed_s(self) -> float:
        return self.now_s - self.started_s

    @property
    def eta_s(self) -> float:
        """Seconds until the arm should be done: what is queued, then what is still unsent (at
        the feed override: motion time taken as inverse to speed, ramps aside)."""
        return self.queued_s + self.remaining_motion_s * 100 / self.feed_percent

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


class _Phase(Enum):
    START = "start"
    STREAMING = "streaming"  # frames of the job still to write
    DRAINING = "draining"  # every frame written: waiting for the arm to finish
    ABORTING = "aborting"  # writing the abort sequence
    SETTLING = "settling"  # waiting for the arm to come to rest after the abort
    DONE = "done"


class Job:
    """One job: ``statements`` (objects with ``command`` and ``line``) paced by ``pacing``,
    judged by ``streamer``; see the module docstring."""

    def __init__(self, streamer, statements: Iterable, view: RunView, *, pacing=None,
                 abort_sequence: tuple = ABORT_SEQUENCES["pause"], control_frames: str | None = None,
                 fifo_proven: bool = True) -> None:
        """``fifo_proven``: the connector's FIFO is known to hold at least the profile's
        ``fifo_frames`` (``armctl.link.fifo_proven`` decides for ``armctl run``)."""
        self.streamer = streamer
        self.fifo_proven = fifo_proven
        streamer.fifo_holds_all = fifo_proven  # else a frame gone from the FIFO may have been dropped, not run
        # pause, resume and the feed override (armctl/job_control.py), under the profile the
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
        # (position and joints as last reported, since when): the arm is at rest when none of
        # them changed for REST_CHECK_S — a wrist turning in place changes only joints.
        self._rest: tuple | None = None
        self._read_at: dict[int, float] = {}  # kind → when it was last read (``known_still_s``)
        self._motion: tuple | None = None  # the same for position and joints alone (no PWM)
        self._moved_from: tuple | None = None  # the readings when they last changed by more than jitter
        self._run_position: float | None = None  # the SD program's run position last reported
        self._active_s: float | None = None  # when the arm last visibly worked (moved, or ran its program)
        self._reported: dict = {}
        self._pause_reports: deque = deque(maxlen=2)  # the last two pause states reported
        self._pause_read_s: deque = deque(maxlen=2)  # ... and when they were read
        self._script_toggles: list = []  # the job's own PAUSE frames written (SentFrame), in order
        self._script_pause_deadline_s: float | None = None  # held behind one: how long its pause is waited for
        self._recent: deque = deque(maxlen=RECENT_FRAMES)  # the last frames written (SentFrame)
        self._aborts: deque = deque()  # abort frames still to write
        self._deadline_s = 0.0
        self._overran = False
        self._write: Write | None = None  # the Write asked for and not yet done
        self._command = None  # the command that Write carries (the feed override applied)
        self._control_version = 0  # the control state the view shows
        self._last_move = None  # the last frame written that moves the arm (its SentFrame)
        self._resume_at_next = False  # frozen where the first pending frame ends and the next begins
        self._held = False  # streaming, and only evidence lets the next frame go (``_rest_proves_all_written``)
        self._found_arrival = False  # the arm proved its control frames act as they land (``_frozen_mid_move``)

    # --- input ------------------------------------------------------------------------------

    def receive_status(self, frame: StatusFrame, now: float) -> bool:
        """Take one status frame read at ``now``.  True when it may change what ``next_action``
        answers; False when it cannot: while streaming, a kind the engine only counts (worktable,
        wrist, SD file length and status), a pause report that changes no control state, a
        position or joints report that moved neither the lower bound nor the streamer's plan
        (``Streamer.plan_changes``: on the same frame's path where the estimate has the arm), or an
        SD run position that did not move, with nothing newly known consumed and no pause asked
        or in force (and, while only evidence lets the next frame go, no rest that may now prove
        every frame written finished) — a virtual-time host reads on past it without asking
        (``Wait``'s promise: nothing changes between status frames but at its time).
        ``receive_statuses`` of one frame."""
        return self.receive_statuses((frame,), (now,)) is not None

    def receive_statuses(self, frames, times) -> int | None:
        """``receive_status`` for each frame of ``frames`` read at the time of ``times`` at the same
        place, in order, up to the first that is news: its place (the frames after it are not
        taken), or None when none was (all taken).  A virtual-time host hands over the frames of
        a simulator's quiet stretch this way (``JobRunner.on_status_run``): one call, not one a frame."""
        streamer, view, control = self.streamer, self.view, self.control
        streamer_receive, reported, read_at = streamer.receive_status, self._reported, self._read_at
        other = self.pacing if self.pacing is not streamer else None
        streaming = self.phase is _Phase.STREAMING
        draining = self.phase is _Phase.DRAINING
        held = self._held and streaming
        deadline_s = self._deadline_s
        rest_values = _REST_VALUES
        k = -1
        for frame in frames:
            k += 1
            now = times[k]
            consumed, plan = streamer.consumed_lower_bound, streamer.plan_changes
            streamer_receive(frame, now)
            # Past streaming every frame is news: the end-of-job checks compare times their own way
            # (``now - since >= REST_CHECK_S``), which may hold a rounding error before the time the
            # Wait named; a frame read then must find them as it always did.
            # Draining, one answer holds until the estimate runs out or the deadline (``_draining``:
            # no rest before the estimated finish, nothing else before the deadline): a frame read
            # before both that moved neither the estimate nor the bound may change only the time of
            # a Wait, never to before either (the host is woken by then, or by a later frame).
            news = control.busy or (not streaming and not (
                draining and streamer.plan_changes == plan and now < deadline_s
                and now < (streamer.estimated_finish_s() or now)))
            if other is not None:
                other.receive_status(frame, now)
                news = True  # another strategy may act on any frame
            kind = frame.KIND
            values_of = rest_values.get(kind)
            if values_of is None:
                if kind == _RUN_POSITION_KIND:
                    if self._run_position is not None and frame.value != self._run_position:
                        self._active_s = now  # an SD program advancing, even with the arm standing still
                        news = True
                    self._run_position = frame.value
                if news or streamer.consumed_lower_bound != consumed:
                    view.status_frames += k + 1
                    return k
                continue
            values = values_of(frame)
            if kind == 4:  # news while streaming only through the control state (or the bound)
                self._pause_reports.append(frame.paused)
                self._pause_read_s.append(now)
                version = control.version
                control.observe(agreed_pause(self._pause_reports))  # pausing… → paused, resuming… → running
                news = news or control.version != version
            else:  # position and joints while streaming: news only through the streamer's
                # evidence (the bound, below) or its plan (the estimate's end times, the pace)
                news = news or streamer.plan_changes != plan
                if kind == 0:
                    view.position_mm = values = streamer.worktable_xyz(values)  # status_xyz_frame
            changed = reported.get(kind) != values  # else so are the readings: _rest and _motion hold them
            reported[kind] = values
            before_s = read_at.get(kind) if changed else None  # the last reading of this kind that differed
            read_at[kind] = now
            if changed or self._rest is None:
                # One kind's values changed (or these are the first readings): the readings differ
                # from the last ``_rest`` (it always holds the readings before this frame), and so
                # does the motion unless only the pause and PWM changed.
                self._rest = ((reported.get(0), reported.get(1), reported.get(2), reported.get(4)), now)
                if kind != 4 or self._motion is None:
                    motion = self._rest[0][:3]
                    moving_s = self._motion[2] if self._motion is not None else None
                    if kind != 4 and before_s is not None and (moving_s is None or before_s > moving_s):
                        moving_s = before_s
                    self._motion = (motion, now, moving_s)
                    moved_from = self._moved_from
                    # Every other kind's readings are within jitter of ``_moved_from`` (checked when
                    # they changed, or equal since it was taken): only this kind's can have moved.
                    if moved_from is None or (kind != 4 and _slot_moved(kind, moved_from[kind], values)):
                        self._moved_from = motion
                        self._active_s = now
            elif held and now - self._rest_since_s() >= REST_CHECK_S:
                news = True  # the rest that may prove every frame written finished (``_rest_proves_all_written``)
            if news or streamer.consumed_lower_bound != consumed:
                view.status_frames += k + 1
                return k
        view.status_frames += k + 1  # (counted once: nothing above reads it)
        return None

    def wrote(self, now: float) -> None:
        """The host wrote the frame the last ``Write`` asked for, starting at ``now``."""
        write, self._write = self._write, None
        if self.phase is _Phase.ABORTING:
            if isinstance(self._aborts.popleft(), ResetConnector) and self._acts_on_arrival:
                self.streamer.cleared()  # it acted as it landed: what was queued may be gone
            return
        if write is not None and write.control is not None:  # a pause toggle the user asked for
            self.control.take_toggle()
            self.streamer.wire_free_s = max(self.streamer.wire_free_s, now) + self.streamer.frame_s
            self._refresh(now)
            return
        view = self.view
        statement = view.next_statement
        command = self._command
        sent = self.streamer.wrote(command, now, tag=statement)
        if self.pacing is not self.streamer:
            self.pacing.wrote(command, now, statement)
        self._recent.append(sent)
        if isinstance(command, PauseToggle):
            self._script_toggles.append(sent)
        if _moves_arm(sent.segment):
            self._last_move = sent
        view.frames_sent += 1
        view.last_sent = statement
        view.next_statement = next(self.statements, None)
        # the estimate's remaining motion is at 100 %: the frame's own time, unscaled
        view.remaining_motion_s = max(0.0, view.remaining_motion_s - sent.segment.duration_s * self.control.feed.percent / 100)
        self._refresh(now)

    def request_stop(self, why: str | None = None) -> None:
        """Stop at the next action: the abort sequence, then wait for rest.  ``why`` (a failure
        the host met, e.g. a --log that cannot be written) makes the outcome FAILED."""
        self.failure = self.failure or why
        self.stop_requested = True

    def pause(self) -> bool:
        """Pause the job: a pause toggle, and nothing more written until ``resume`` (False when
        already pausing or paused, the arm reports it is paused, or the job is stopping)."""
        # (not behind the script's own PAUSE: a second toggle would undo it, or, queued, resume the arm
        # it paused)
        return self._controllable and len(self._script_toggles) % 2 == 0 and self.control.pause()

    def resume(self) -> bool:
        """Resume a pause asked with ``pause``: the toggle goes first, then the job's frames."""
        return self._controllable and self.control.resume()

    @property
    def _controllable(self) -> bool:
        """Pause and resume act while the job streams or drains; a stop has its own sequence."""
        return not self.stop_requested and self.phase in (_Phase.START, _Phase.STREAMING, _Phase.DRAINING)

    def set_feed_override(self, percent: int) -> int:
        """Rescale the speed of the frames not yet written (10…200 %, 10 % steps); returns the
        percentage in force."""
        return self.control.set_feed_override(percent)

    def port_lost(self, why: str | None = None) -> None:
        """The port went away: nothing more can be written or read."""
        if why:
            self.view.messages.append(why)
        self._finish(Outcome.PORT_LOST, self.view.now_s)

    # --- output -----------------------------------------------------------------------------

    def next_action(self, now: float) -> Write | Wait | Finished:
        """What the host does next; asking again without news gives the same answer."""
        if self.outcome is not None:
            return Finished(self.outcome)
        view = self.view
        if self.phase is _Phase.START:
            view.started_s = now
            view.next_statement = next(self.statements, None)
            self.phase = _Phase.STREAMING
        if self.stop_requested and self.phase in (_Phase.STREAMING, _Phase.DRAINING):
            self._begin_abort()
        self._refresh(now)
        if self.control.busy and self.phase in (_Phase.STREAMING, _Phase.DRAINING):
            held = self._control_action(now)
            if held is not None:
                return held
        if self.phase is _Phase.STREAMING:
            statement = view.next_statement
            if statement is not None and self._script_pause_holds(statement):
                return self._held_by_script_pause(now)
            if statement is not None:
                command = self.control.command_for(statement)
                when = self.pacing.next_write_time(now, command)
                self._held = when is None and self.pacing is self.streamer
                if self._held and self.streamer.pending:
                    before = self._rest_proves_done_before(now)
                    if before is not None and before > self.streamer.pending[0].index:
                        self.streamer.confirm_all_done(now, before)  # (the time bound's chain restarts at now)
                        when = self.pacing.next_write_time(now, command)
                if when is not None and when <= now:
                    if self._write is None:
                        self._write, self._command = Write(command.encode(), statement), command
                    return self._write
                return Wait(when)
            self.phase = _Phase.DRAINING
            self._deadline_s = self._settle_deadline(now)
        if self.phase is _Phase.DRAINING:
            return self._draining(now)
        if self.phase is _Phase.ABORTING:
            if self._aborts:
                if self._write is None:
                    self._write = Write(self._aborts[0].encode(), None)
                return self._write
            self.phase = _Phase.SETTLING
            self._deadline_s = self._settle_deadline(now)
        return self._settling(now)

    def _control_action(self, now: float) -> Write | Wait | None:
        """A pause toggle the user asked for goes as soon as the wire is free — never behind the
        streamer's capacity or lead, so a resume is not held behind a FIFO it counts as full;
        while a pause is asked or in force nothing else is written, and the end of the job
        waits (its deadline starts again from the resume).  None: carry on."""
        control = self.control
        if control.toggle_due:
            if self._write is not None and self._write.statement is not None:
                self._write = None  # a frame asked for and not written yet: the toggle goes first
            wire_s = self.streamer.wire_free_s
            if wire_s > now:
                return Wait(wire_s)
            if self._write is None:
                self._write = Write(PauseToggle().encode(), None, "pause toggle")
            return self._write
        if control.holds_feed:
            if self.phase is _Phase.DRAINING:
                self._deadline_s = self._settle_deadline(now)
            return Wait(None)  # until the arm reports (pausing → paused) or the user resumes
        return None

    def _script_pause_holds(self, statement) -> bool:
        """The job's own PAUSE lines left the arm to pause (an odd number written) and the next
        statement does not resume it: nothing more is written.  On an arm whose control frames
        queue (H5) a frame behind the PAUSE would wait at the head of the paused FIFO, where no
        resume toggle could ever reach the head; on either arm the rest of the job waits for a
        resume nobody in this run can give (the run ends at the pause: ``_held_by_script_pause``)."""
        return len(self._script_toggles) % 2 == 1 and not isinstance(statement.command, PauseToggle)

    def _paused_by_script(self) -> bool:
        """The arm reports it is paused (two agreeing reports) in reports read after the job's last
        PAUSE landed: it acted — and, queued (H5), after every frame before it had run; on
        arrival, rule (c) wrote it only once they had."""
        toggles = self._script_toggles
        if len(toggles) % 2 == 0 or self.arm_paused is not True or len(self._pause_read_s) < 2:
            return False
        return self._pause_read_s[0] >= toggles[-1].wire_end_s + ARRIVAL_SLACK_S

    def _script_pause_line(self):
        return getattr(self._script_toggles[-1].tag, "line", None)

    def _held_by_script_pause(self, now: float) -> Wait | Finished:
        """Held behind the script's own PAUSE: once the arm reports the pause, every frame written
        ran, and the run ends "paused by the script" with the resume line after the PAUSE (the
        resume's start-up un-pauses the arm with its one toggle, its FIFO empty).  An arm that
        does not report the pause in the time its queue takes ends "no confirmation"."""
        if self._paused_by_script():
            self._script_toggles[-1].seen = True  # the arm's pause report: it ran
            self.streamer.confirm_all_done()
            following = getattr(self.view.next_statement, "line", None)
            self.view.messages.append(
                f"paused by the script's PAUSE at line {self._script_pause_line()}: the arm is paused, and the rest "
                f"of the job (from line {following}) was not sent; the printed resume un-pauses the arm and runs it")
            return self._finish(Outcome.PAUSED, now)
        if self._script_pause_deadline_s is None:
            self._script_pause_deadline_s = self._settle_deadline(now)
        if now >= self._script_pause_deadline_s:
            self.view.messages.append(f"the arm did not report the pause of the script's PAUSE at line "
                                      f"{self._script_pause_line()} in time: the rest of the job was not sent")
            return self._finish(Outcome.FRAMES_LOST if self.streamer.losses else Outcome.NO_CONFIRMATION, now)
        return Wait(self._script_pause_deadline_s)

    @property
    def streaming(self) -> bool:
        """Frames of the job are still to be written (the pacing strategy's answers are current)."""
        return self.phase is _Phase.STREAMING

    @property
    def aborting(self) -> bool:
        """Frames of the abort sequence are being written (a write that fails now did not stop the arm)."""
        return self.phase is _Phase.ABORTING

    # --- the end ----------------------------------------------------------------------------

    def _settle_deadline(self, now: float) -> float:
        """How long the end is waited for: the motion queued at the slowest pace, and no earlier
        than the frames after the last motion can surely be done (a long run of delays leaves
        no trace: only time tells, and an arm twice slower needs twice theirs)."""
        streamer = self.streamer
        return max(now + streamer.queued_seconds(now) * streamer.slowest_factor, self._trailing_done_s()) + SETTLE_SLACK_S

    def _draining(self, now: float) -> Wait | Finished:
        """Finished means: at rest, at the last target, not paused, and the estimate agrees.
        Anything else ends without claiming the job ran (frames cleared or dropped, a pause)."""
        view = self.view
        paused_at_end = self._paused_by_script()  # the script ends with its own PAUSE: every frame ran
        if paused_at_end:
            self._script_toggles[-1].seen = True
        if paused_at_end or self._rest_proves_all_written(now):
            self._confirm_all_done()
            view.arm_done_s = self._done_at(now)
            if paused_at_end:
                view.messages.append(f"the arm is paused, as the script's PAUSE at line {self._script_pause_line()} "
                                     "leaves it")
            if self._overran:
                view.messages.append("the arm kept working past the estimate (moving, or running an SD program "
                                     "whose time armctl cannot know); armctl waited until it stopped")
            self._check_job_time(view.arm_done_s)
            return self._finish(self._finished_outcome(), now)
        limit_s = self._deadline_s
        if now >= self._deadline_s:
            # Visibly working: the job is still running, whatever the estimate says; once it
            # stops, there is time to confirm it is where the job ends.
            active = self._active_s is not None and now - self._active_s < REST_CHECK_S
            self._overran = self._overran or active
            settle_until = [self._active_s + REST_CHECK_S + SETTLE_SLACK_S] if self._overran else []
            if self._rest is not None and now - self._rest_since_s() >= REST_CHECK_S > self._rest_s():
                # Still for long enough, but some kind not re-read since (its reports lost): the
                # next reports may yet prove the rest — waited for as for an arm that just stopped.
                settle_until.append(self._rest_since_s() + REST_CHECK_S + SETTLE_SLACK_S)
            resting = self._resting_before_last_move()
            if resting:  # frames rest cannot prove: their time bound (widened by a slow pace) decides
                settle_until.append(max(sent.certain_end_s for sent in resting) + SETTLE_SLACK_S)
            limit_s = min(self._deadline_s + self._overrun_limit_s(), max(settle_until, default=now))
            if now >= limit_s:
                view.messages.append(self._why_not_finished())
                lost = bool(self.streamer.losses)
                return self._finish(Outcome.FRAMES_LOST if lost else Outcome.NO_CONFIRMATION, now)
        return Wait(self._next_change_s(now, limit_s))

    def _rest_proves_all_written(self, now: float) -> bool:
        """Every frame written has finished (``_rest_proves_done_before`` leaves none unproven).
        The end of a job rests on it, and so does a job held mid-way (the FIFO bound, or rule
        (c), with only evidence to let the next frame go): it is what confirms an arc from an
        unverified joint end when no later frame's sighting can (armctl/streamer.py
        ``_unknown_start_s``: time cannot) — the arm has drained its FIFO by then, which costs
        the job that wait, never a frame."""
        return self._rest_proves_done_before(now) == self.streamer.sent

    def _rest_proves_done_before(self, now: float) -> int | None:
        """The first frame the arm's rest at the last target (not paused, at rest since every
        frame written came: ``_rest_since_s``) leaves unproven, or None when it proves nothing.
        The frames after the last motion (a delay, M codes, PWM-only moves) leave no trace: an
        arm at rest at the last target says nothing about them, and an arm slower than the model
        would still be in them when the estimate runs out; they count as done once even an arm
        ``slowest_factor`` times slower has finished them (``_trailing_done_s``) — then every
        frame written has run (``streamer.sent``).  And the arm rests as well in such a frame
        before the last motion, at readings the last target's may be (a wrist turning in place,
        a way back to the same point: ``_resting_before_last_move``): then the arm is in such a
        run or past the last frame, so only the frames before the first of them have run (an arc
        that time cannot bound among them; held mid-job, the rest of them wait for the lower
        bound: the arm seen on a later frame's path, or their time bound)."""
        if not (self.arm_at_rest(now) and self._at_last_target() and self.arm_paused is False):
            return None
        resting = self._resting_before_last_move()
        if resting:
            return resting[0].index
        return self.streamer.sent if now >= self._trailing_done_s() else None

    def _resting_before_last_move(self) -> list:
        """The frames still pending before the last motion that move nothing (``_moves_arm``), in
        runs between moves that could hold the arm still for ``REST_CHECK_S``: even an arm
        ``slowest_factor`` times slower, fed each frame at the line's pace, leaves a shorter run
        (a G54, an M code) before the rest check could see it still — and where the arm rests
        there may read as the last target in one of them (``_may_read_as_end_of``; a G54 among
        them changes what the worktable X/Y/Z read): at rest far from it, the arm is plainly not
        done."""
        last = self._last_move
        if last is None:
            return []
        streamer, resting, run, hold_s = self.streamer, [], [], ARRIVAL_SLACK_S
        target = self._recent[-1].segment  # what ``_at_last_target`` compares the readings with
        for sent in streamer.pending:
            if sent.index >= last.index or _moves_arm(sent.segment) or isinstance(sent.command, ArcStart):
                if hold_s >= REST_CHECK_S and any(self._may_read_as_end_of(r.segment.end, target) for r in run):
                    resting += run  # (a G300 runs with its G301: no rest in it)
                run, hold_s = [], ARRIVAL_SLACK_S
                if sent.index >= last.index:
                    break
                continue
            run.append(sent)
            hold_s += sent.segment.duration_s * streamer.slowest_factor + streamer.frame_slack_s + streamer.frame_s
        return resting

    def _trailing_done_s(self) -> float:
        motion_end_s = self._motion[1] if self._motion is not None else 0.0
        streamer, slowest = self.streamer, self.streamer.slowest_factor
        # every frame after the last one that moves, however many (the recent ones are only the
        # last RECENT_FRAMES): their model time at the slowest pace, from the end of that motion …
        last = self._last_move
        moved_until_s = 0.0 if last is None else last.motion_before_s + last.segment.duration_s
        count = streamer.sent - (0 if last is None else last.index + 1)
        all_s = motion_end_s + (streamer.motion_sent_s - moved_until_s) * slowest + count * streamer.frame_slack_s
        # … and no earlier than the chain over the recent ones, each begun no earlier than it arrived
        trailing = []
        for sent in reversed(self._recent):
            if _moves_arm(sent.segment):
                break
            trailing.append(sent)
        done_s = motion_end_s
        for sent in reversed(trailing):
            done_s = (max(done_s, sent.wire_end_s + ARRIVAL_SLACK_S) + sent.segment.duration_s * slowest
                      + streamer.frame_slack_s)
        return max(done_s, all_s)

    def _check_job_time(self, done_s: float) -> None:
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
        streamer.losses.append(
            f"the arm was at rest at the last target {arm_s:.1f} s after the first frame, but the frames sent take "
            f"{streamer.sure_motion_sent_s:.1f} s of motion (at least {least_s:.1f} s on an arm "
            f"{1 / streamer.fastest_factor:g}x faster than the model): some were not run (dropped by a full FIFO?)")
        suspect = streamer.first_time_only_index or 0
        if streamer.first_suspect_index is None or suspect < streamer.first_suspect_index:
            streamer.first_suspect_index = suspect

    def _finished_outcome(self) -> Outcome:
        """FINISHED only when nothing says a frame was lost and the claim rests on proof."""
        streamer = self.streamer
        if streamer.losses:
            return Outcome.FRAMES_LOST
        if not self.fifo_proven and (streamer.confirmed_by_time or streamer.confirmed_unseen):
            self.view.messages.append(
                f"finished, unproven: {_frames_not_seen(streamer)}, and the FIFO size is the document's, not "
                "measured on this arm: a frame it dropped would look the same; run `armctl probe` once")
            return Outcome.UNPROVEN
        return Outcome.FINISHED

    def _settling(self, now: float) -> Wait | Finished:
        """After the abort sequence: until the arm is at rest — paused (the estimate cannot know
        for how long) or with the job's time over — or the deadline."""
        outcome = Outcome.FAILED if self.failure else Outcome.INTERRUPTED
        if now >= self._deadline_s:
            return self._finish(outcome, now)
        still = self._rest_s() >= REST_CHECK_S
        if still and (self.arm_paused or self.arm_at_rest(now)):
            if self.arm_paused and not self._acts_on_arrival and self._paused_on_arrival():
                return self.next_action(now)  # the RESET CONNECTOR that clears what is still queued
            if self.arm_paused and self._acts_on_arrival:
                # The pause acted as it landed: the arm at the last target says nothing of the frames
                # after its last move (a PWM change, a delay: the RESET CONNECTOR cleared them, or
                # not); the moves it reached the ends of did run.
                self._confirm_through_last_move()
                self._resume_at_next = self._frozen_at_a_boundary()
            elif self._at_last_target():
                self._confirm_all_done()
            return self._finish(outcome, now)
        return Wait(self._next_change_s(now, self._deadline_s))

    def _next_change_s(self, now: float, limit_s: float) -> float:
        """The first time after ``now`` at which, with no new status frame, the answer could
        change: a rest or activity check maturing, the estimate running out, the deadline
        (``limit_s``, always after ``now``: a Wait never asks the host to wait for nothing)."""
        times = [limit_s]
        if self._rest is not None:
            times.append(self._rest_since_s() + REST_CHECK_S)
        if self._active_s is not None:
            times.append(self._active_s + REST_CHECK_S)
        finish = self.streamer.estimated_finish_s()
        if finish is not None:
            times += (finish, self._trailing_done_s())
        return min((t for t in times if t > now), default=limit_s)

    def _finish(self, outcome: Outcome, now: float) -> Finished:
        view = self.view
        if outcome in (Outcome.FAILED,) and self.failure:
            view.messages.append(self.failure)
        view.messages.extend(self.streamer.losses)
        self.outcome = outcome
        self.phase = _Phase.DONE
        view.outcome = outcome
        self._refresh(now)
        return Finished(outcome)

    def _begin_abort(self) -> None:
        """Nothing more of the job is written; the abort sequence goes instead.  A pause toggle
        is not sent to an arm that reports it is paused: it would resume it."""
        view = self.view
        view.outcome = Outcome.INTERRUPTED
        sequence = self.abort_sequence
        if self.streamer.control_on_arrival and sequence == abort_frames("pause", True):
            view.messages.append("the arm acts on control frames as they land: the pause froze the move in progress "
                                 "and a RESET CONNECTOR cleared the frames queued behind it; the resume command resumes "
                                 "that move, then re-sends its line (an absolute move to where the arm then is)")
        self.control.observe(self.arm_paused)
        script_pause = len(self._script_toggles) % 2 == 1  # the script's own PAUSE pauses (or paused) it
        if (script_pause or not self.control.abort_needs_toggle()) and any(isinstance(c, PauseToggle) for c in sequence):
            why = (f"the script's PAUSE at line {self._script_pause_line()} was already written"
                   if script_pause and self.arm_paused is not True
                   else "a pause was already on its way" if self.control.state == "pausing"
                   else "the arm was already paused")
            view.messages.append(f"{why}: no pause toggle sent (it would have resumed it)")
            sequence = tuple(c for c in sequence if not isinstance(c, PauseToggle))
        self._aborts = deque(sequence)
        self._write = None
        self.phase = _Phase.ABORTING

    def arm_at_rest(self, now: float) -> bool:
        """The arm reported the same position, joints and PWM for REST_CHECK_S and the estimate
        says the job is over."""
        finish = self.streamer.estimated_finish_s()
        if finish is not None and now < finish:
            return False
        if self._active_s is not None and now - self._active_s < REST_CHECK_S:
            return False  # an SD program still advancing, even with the arm standing still
        return self._rest_s() >= REST_CHECK_S

    def _rest_s(self) -> float:
        """How long the readings of every kind (position, joints 1-3, joints 4-6, pause and PWM)
        are known unchanged (``known_still_s``; 0 until each kind was read once)."""
        if self._rest is None or len(self._read_at) < len(_REST_VALUES):
            return 0.0
        return known_still_s(self._rest_since_s(), self._read_at.values())

    def _rest_since_s(self) -> float:
        """Since when the readings prove a rest: their last change, or the arrival of the last
        frame written if later — a frame that came while the arm stood still may set it going
        (its own IK elsewhere) after the readings were taken."""
        since = self._rest[1]
        if self._recent:
            since = max(since, self._recent[-1].wire_end_s + ARRIVAL_SLACK_S)
        return since

    @property
    def arm_paused(self) -> bool | None:
        """The pause state when the last two pause reports agree (``agreed_pause``)."""
        return agreed_pause(self._pause_reports)

    def _at_last_target(self) -> bool:
        """The arm reports the end of the last frame written (joints for a joint move)."""
        if not self._recent:
            return True
        return self._at_end_of(self._recent[-1].segment)

    def _at_end_of(self, segment) -> bool:
        """The arm reports the end of ``segment`` (joints for a joint move)."""
        if segment.kind == "joint" or segment.end.xyz_derived:  # what the arm reports, not the profile's FK
            joints = (self._reported.get(1) or ()) + (self._reported.get(2) or ())
            return len(joints) == 6 and max(abs(a - b) for a, b in zip(joints, segment.end.joints)) <= TARGET_DEG
        position = self._reported.get(0)
        return position is not None and max(abs(a - b) for a, b in zip(position, segment.end.xyz)) <= TARGET_MM

    def _may_read_as_end_of(self, pose, segment) -> bool:
        """Whether an arm at rest at the model's ``pose`` may report what ``_at_end_of(segment)``
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

    def _done_at(self, now: float) -> float:
        """When the arm finished: the end of its last motion seen, plus the model's time for
        the frames after that motion, which move nothing (delays, M codes, control frames,
        PWM-only moves, a move to where the arm already is); never before the last change
        seen at all (a PWM report), never after now."""
        if self._motion is None:  # set with _rest: nothing reported yet
            return now
        # every frame after the last one that moves, however many (not only the recent ones)
        last = self._last_move
        moved_until_s = 0.0 if last is None else last.motion_before_s + last.segment.duration_s
        trailing_s = self.streamer.motion_sent_s - moved_until_s
        _, seen_s, moving_s = self._motion
        done = max(seen_s + trailing_s, self._rest[1], self._active_s or 0.0)
        if moving_s is not None and last is not None and done == seen_s + trailing_s:
            # Every kind of reading had its last value by ``seen_s``, and one still differed from
            # it at ``moving_s`` (the latest such reading): the arm stopped in between, up to a
            # rotation before ``seen_s`` (kinds 0-2 come together, then 210 ms of others), so the
            # end is the estimate's where it lies in that window, else its middle (``seen_s`` made
            # a 2.63 s job read 2.79 s at 115200 baud).
            end_s = last.est_end_s
            done = (end_s if moving_s <= end_s <= seen_s else (moving_s + seen_s) / 2) + trailing_s
        return min(done, now)

    def _overrun_limit_s(self) -> float:
        """How long past the deadline a visibly working arm is waited for: readings that
        jitter or are corrupted look like work, so the wait must end (an SD program longer
        than this ends "no confirmation")."""
        return max(OVERRUN_MIN_S, self.view.estimated_job_s)

    def _why_not_finished(self) -> str:
        if self.arm_paused:
            return "the arm reports it is paused: the rest of the job waits in its buffer"
        position = self._reported.get(0)
        if self._rest is not None and position is not None and self._recent and not self._at_last_target():
            named = self._arms_own_motion_last()
            if named is not None:
                return named
            return (f"the arm stopped at ({_values(position)}) but the job's last target is "
                    f"({_values(self._recent[-1].segment.end.xyz)}): "
                    "frames were lost, cleared or refused (a RESET CONNECTOR, a full buffer, a target out of the arm's reach?)")
        return "the arm did not confirm the end of the job in time (status frames missing?)"

    def _arms_own_motion_last(self) -> str | None:
        """Why the arm is not at the last target when the job's last positioning frame is one
        whose motion is the arm's own, not the job's: a ``POSE n`` goes to the arm's fixed pose,
        which the profile's ``[poses]`` only describe, and a ``PROGRAM n`` runs an SD program
        armctl cannot see into.  Named as such (None when no such frame comes after the job's own
        last motion): the arm's rest elsewhere is no sign that frames were lost."""
        for sent in reversed(self._recent):
            command = sent.command
            where = f"line {sent.tag.line}" if getattr(sent.tag, "line", None) is not None else f"frame {sent.index + 1}"
            if isinstance(command, RunProgram):
                return (f"the arm stopped at ({_values(self._reported.get(0))}) after PROGRAM {command.program} ({where}): "
                        "an SD program moves the arm as it says, which armctl cannot know, so where it rests proves "
                        "nothing about the job's frames")
            if isinstance(command, GoToPose):
                joints = (self._reported.get(1) or ()) + (self._reported.get(2) or ())
                return (f"POSE {command.pose} ({where}) should end at the profile's fixed pose {command.pose} (joints "
                        f"{_values(sent.segment.end.joints)}), but the arm stopped at joints ({_values(joints)}): its own "
                        f"fixed pose {command.pose} is not the profile's [poses] (or the frame did not run)")
            if _moves_arm(sent.segment):
                return None  # the job's own move after it says where the arm should be
        return None

    def _confirm_all_done(self) -> None:
        self.streamer.confirm_all_done()

    # --- the view ---------------------------------------------------------------------------

    def _refresh(self, now: float) -> None:
        view, streamer = self.view, self.streamer
        view.now_s = now
        view.queued_frames_bound = streamer.frames_in_flight_bound
        view.queued_s = streamer.queued_seconds(now)
        view.last_done = streamer.last_known_done()
        view.first_not_done = self._first_not_done()
        control = self.control  # it follows the pause reports as they come (receive_status)
        if control.version != self._control_version:  # the view follows only a change
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

    def _paused_on_arrival(self) -> bool:
        """On an arm the profile says queues its control frames (H5), the abort's pause acted as it
        landed — the arm paused with frames still queued behind it, which the next run's toggle
        would release to run before its resume line re-sends them: then a RESET CONNECTOR goes
        (it acts as it lands too, on such an arm) and True.  Proven only by the arm frozen
        mid-move (``_frozen_mid_move``: a queued pause acts only between frames): on a queued arm
        the same RESET CONNECTOR would wait at the head of its paused FIFO for ever, and a pause
        that merely came sooner than the queue could run is what a FIFO that dropped frames
        shows too.  (Frozen in a frame that moves nothing — a PWM change, a delay — such an arm
        shows nothing: `armctl probe` measures the mode.)"""
        if self._found_arrival or self._aborts or not self._frozen_mid_move():
            return False
        self._found_arrival = True
        self.view.messages.append(
            "the arm paused mid-move with frames still queued: its control frames act as they land, though the "
            "profile says they queue (run `armctl probe`); a RESET CONNECTOR cleared the queue, so the resume runs "
            "nothing twice")
        self._aborts.append(ResetConnector())
        self.phase = _Phase.ABORTING
        return True

    def _confirm_through_last_move(self) -> None:
        """The arm at rest at the end of the last frame written that moves it (its target where no
        other frame kept ends or it starts: ``Streamer.ran_at_rest``): it and every frame before it ran."""
        last = self._last_move
        if last is not None and self._at_end_of(last.segment) and self.streamer.ran_at_rest(last):
            last.seen = True
            self.streamer.confirm_all_done(before=last.index + 1)
            return
        # Else the first pending frame whose path holds where the arm rests: at its end, its motion
        # is over (the arm is there, or on a later frame), so it is not re-sent; anywhere else on
        # it, the arm is frozen in it.  Judged in what the arm reports, frame by frame in order,
        # up to a frame whose pose that cannot judge.
        position = self._reported.get(0)
        joints = (self._reported.get(1) or ()) + (self._reported.get(2) or ())
        verified, origin = self.streamer.kinematics_verified, self.streamer.planner.pose.origin_mm
        for sent in self.streamer.pending:
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
            if _moves_arm(segment) and max(abs(a - b) for a, b in zip(end, observed)) <= near:
                self.streamer.confirm_all_done(before=sent.index + 1)
            return

    @property
    def _acts_on_arrival(self) -> bool:
        """The arm's control frames act as they land: the profile says so, or the arm showed it."""
        return self.streamer.control_on_arrival or self._found_arrival

    def _frozen_mid_move(self) -> bool:
        """The arm, paused and still, rests strictly inside the path of a frame still pending — at
        no frame's end, where a pause queued behind the frames (H5) would leave it (an arm that
        dropped frames too): only a pause that acted as it landed freezes a move there.  Judged
        on what the arm reports: X/Y/Z on a line or arc, joints on a joint move, each on a path
        the plan knows."""
        position = self._reported.get(0)
        joints = (self._reported.get(1) or ()) + (self._reported.get(2) or ())
        streamer = self.streamer
        ends = [sent.segment for sent in self._recent] + list(sent.segment for sent in streamer.pending)
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

    def _frozen_at_a_boundary(self) -> bool:
        """A pause that acted as it landed froze the arm at the end of the first pending frame
        (or on it, if it moves nothing), i.e. at the start of the next, a move: either is the
        frozen one.  The resume toggle
        finishes it, so the resume line is the next frame: run once if the arm was on the first,
        re-sent to where the arm then is (idempotent) if it was on the next.  (Resuming at the
        first would drive the arm back to its end after the next had finished.)"""
        pending = self.streamer.pending
        if len(pending) < 2 or not _moves_arm(pending[1].segment) or isinstance(pending[1].command, CONTROL_COMMANDS):
            return False
        return self._at_end_of(pending[0].segment)  # a first frame that moves nothing: the arm is at its end

    def _first_not_done(self):
        pending = self.streamer.pending
        if self._resume_at_next and len(pending) > 1:
            return pending[1].tag
        if not pending:
            return self.view.next_statement
        if isinstance(pending[0].command, ArcEnd) and self.view.last_done is not None:
            return self.view.last_done  # a G301 cannot be resumed alone: resume at its G300
        return pending[0].tag


def _values(values) -> str:
    return ", ".join(f"{v:.1f}" for v in values or ())


def _frames_not_seen(streamer) -> str:
    """The frames the arm's reports did not see run, as the summary says it."""
    parts = []
    if streamer.confirmed_by_time:
        parts.append(f"{streamer.confirmed_by_time} frames were confirmed by time alone")
    if streamer.confirmed_unseen:
        parts.append(f"{streamer.confirmed_unseen} only by a report on a later frame (gone from the FIFO, "
                     "never seen running)")
    return " and ".join(parts)


def _moves_arm(segment) -> bool:
    """Whether a frame's motion changes the reported position or joints (the motion model's
    ``Segment.moves_reported``: not a move of E0/E1 alone, which no status kind reports)."""
    return segment.moves_reported


def _moved_clearly(before: tuple, after: tuple) -> bool:
    """Position (kind 0) or joints (kinds 1, 2) changed by more than a reading's jitter."""
    return any(_slot_moved(kind, old, new) for kind, (old, new) in enumerate(zip(before, after)))


def _slot_moved(kind: int, old: tuple | None, new: tuple | None) -> bool:
    """One kind's readings (0 position, 1 and 2 the joint halves) changed by more than jitter."""
    if old is None or new is None:
        return old is not new
    limit = TARGET_MM if kind == 0 else TARGET_DEG  # unrolled (three readings a kind): every moving status frame
    a, b, c = old
    x, y, z = new
    return abs(a - x) > limit or abs(b - y) > limit or abs(c - z) > limit
