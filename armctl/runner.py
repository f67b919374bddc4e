"""``armctl run``'s engine: the pure Streamer driven by a clock against an open Link.

Strategy: the edge where time is real.  The link's reader thread only queues status frames
with the time they were read; this module's single thread drains that queue into the
streamer, asks it when the next frame may go, writes it, and sleeps until the next decision
is due.  Everything it knows is in ``RunView`` (for the live panel and the summary); every way
a job can end — finished, Ctrl-C, a lost port, a failure such as a --log that cannot be
written — leaves a ``RunView`` that says the last line sent, the last line known executed and
where to resume.  A failure the runner meets itself (``fail``) takes the Ctrl-C path: it asks
to stop at the next safe point, and the caller sends the abort sequence.

With ``-v`` it tells the pacing story through ``logging`` (logger ``armctl.runner``): the
streamer leaves why it decided as data (``write_reason``, ``bound_evidence``) and this edge logs
a line only when that reason changes, so a long job reads as a few lines, not one per frame.
"""

from __future__ import annotations

import json
import logging
import queue
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Callable, Iterator

from .errors import ArmctlError, PortError
from .protocol import ArcEnd, Command, PauseToggle, ResetConnector, RunPositionStatus, StatusFrame
from .streamer import Evidence, Streamer, WaitReason

_logger = logging.getLogger(__name__)

ABORT_SEQUENCES = {
    "pause": (PauseToggle(),),  # H5: takes effect after the frames already queued
    "reset-connector": (ResetConnector(),),  # clears the FIFO when it acts (queued frames are lost)
    "none": (),
}
REST_CHECK_S = 0.6  # the arm counts as at rest when it reported the same pose this long
SETTLE_SLACK_S = 2.0  # beyond the estimate, how long to wait for the arm to come to rest
POLL_S = 0.05
OVERRUN_MIN_S = 60.0  # the least time waited past the estimate for an arm still working
TARGET_MM = 0.5  # how close the reported position must be to the last target (0.1 mm resolution)
TARGET_DEG = 0.2
_REST_KINDS = (0, 1, 2, 4)  # position, joints 1-3, joints 4-6, pause and PWM
# -v: the wire is told as the reason only once this many frames in a row waited for it alone
# (about a second at 9600 baud): between frames held back by the lead or the FIFO, the line's
# own pace between two writes is not news, and telling it would alternate with them frame by frame.
WIRE_STORY_FRAMES = 20


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
    outcome: str = "running"  # running, finished, interrupted, port lost, no confirmation
    messages: list = field(default_factory=list)

    @property
    def elapsed_s(self) -> float:
        return self.now_s - self.started_s

    @property
    def eta_s(self) -> float:
        """Seconds until the arm should be done: what is queued, then what is still unsent."""
        return self.queued_s + self.remaining_motion_s

    first_not_done: object = None  # the Statement to resume at: the first not known finished

    @property
    def frames_known_done(self) -> int:
        """Frames the streamer knows finished (its lower bound): the ones written and not queued."""
        return max(0, self.frames_sent - self.queued_frames_bound)

    def resume_line(self) -> int | None:
        """The line ``--from-line`` should name to continue after the last line known executed."""
        return None if self.first_not_done is None else self.first_not_done.line


class Aborted(ArmctlError):
    """The user stopped the job (Ctrl-C); the view says where."""


class JobRunner:
    """Streams compiled statements through ``link`` with ``streamer``'s pacing."""

    def __init__(
        self,
        link,
        streamer: Streamer,
        statements: Iterator,
        view: RunView,
        *,
        clock: Callable[[], float] = time.monotonic,
        time_scale: float = 1.0,
        log=None,
        on_update: Callable[[RunView], None] | None = None,
        durations: Callable[[Command], float] | None = None,
    ) -> None:
        self.link = link
        self.streamer = streamer
        self.statements = iter(statements)
        self.view = view
        self.virtual = getattr(link, "is_virtual", False)
        if self.virtual:  # sim://?clock=virtual: the link's clock is model time already
            clock, time_scale = link.clock, 1.0
        self.time_scale = time_scale
        self._wall = clock
        self._wall_origin = clock()
        self.log = log
        self.on_update = on_update or (lambda view: None)
        self.status_queue: queue.SimpleQueue = queue.SimpleQueue()
        # (position and joints as last reported, since when): the arm is at rest when none of
        # them changed for REST_CHECK_S — a wrist turning in place changes only joints.
        self._rest: tuple | None = None
        self._motion: tuple | None = None  # the same for position and joints alone (no PWM)
        self._moved_from: tuple | None = None  # the readings when they last changed by more than jitter
        self._run_position: float | None = None  # the SD program's run position last reported
        self._active_s: float | None = None  # when the arm last visibly worked (moved, or ran its program)
        self._reported: dict = {}
        self._pause_reports: deque = deque(maxlen=2)  # the last two pause states reported
        self._recent: deque = deque(maxlen=64)  # the last frames written (SentFrame)
        self.stop_requested = False
        self.failure: str | None = None  # why the job stopped, when not by Ctrl-C (``fail``)
        self._told_wait: WaitReason | None = None  # the last wait reason logged
        self._wire_frames = 0  # frames in a row that waited for the wire alone (WIRE_STORY_FRAMES)
        self._wire_counted_at = -1  # frames_sent when a wire wait was last counted (once a frame)
        self._told_evidence: Evidence | None = None  # the last evidence logged

    # --- time -------------------------------------------------------------------------------

    def now(self) -> float:
        """Model time: wall seconds × the simulator's time scale (1 for a real arm)."""
        return (self._wall() - self._wall_origin) * self.time_scale

    def _sleep(self, model_s: float) -> None:
        """Wait up to ``model_s`` for a status frame (returns early when one arrives)."""
        if self.virtual:  # the link moves the clock; frames come through on_status meanwhile
            self.link.idle(model_s)
            return
        try:
            item = self.status_queue.get(timeout=max(model_s, 0.0) / self.time_scale)
        except queue.Empty:
            return
        self._take_status(*item)

    # --- status -----------------------------------------------------------------------------

    def on_status(self, frame: StatusFrame, _read_s: float) -> None:
        """Called by the link's reader thread: queue the frame with its model time."""
        self.status_queue.put((frame, self.now()))

    def _drain(self) -> None:
        while True:
            try:
                item = self.status_queue.get_nowait()
            except queue.Empty:
                return
            self._take_status(*item)

    def _take_status(self, frame: StatusFrame, at_s: float) -> None:
        self.streamer.receive_status(frame, at_s)
        self._explain_bound(at_s)  # the streamer names new evidence only when the bound moved
        self.view.status_frames += 1
        if self.log is not None:
            self._log("rx", frame.encode(), at_s, kind=frame.KIND)
        if frame.KIND == 4:
            self._pause_reports.append(frame.paused)
        if frame.KIND in _REST_KINDS:
            values = tuple(frame.fields().values())
            if frame.KIND == 0:
                self.view.position_mm = values
            self._reported[frame.KIND] = values
            reported = tuple(self._reported.get(kind) for kind in _REST_KINDS)
            if self._rest is None or self._rest[0] != reported:
                self._rest = (reported, at_s)
            motion = reported[:3]
            if self._motion is None or self._motion[0] != motion:
                self._motion = (motion, at_s)
            if self._moved_from is None or _moved_clearly(self._moved_from, motion):
                self._moved_from = motion
                self._active_s = at_s
        elif frame.KIND == RunPositionStatus.KIND:
            if self._run_position is not None and frame.value != self._run_position:
                self._active_s = at_s  # an SD program advancing, even with the arm standing still
            self._run_position = frame.value

    # --- the job ----------------------------------------------------------------------------

    def run(self) -> RunView:
        """Stream every statement, then wait for the arm to finish. Raises KeyboardInterrupt
        (after the abort path has run) or PortError (after updating the view)."""
        view = self.view
        view.started_s = view.now_s = self.now()
        view.next_statement = next(self.statements, None)
        try:
            while view.next_statement is not None:
                self._step()
            self._wait_for_finish()
        except PortError:
            view.outcome = "port lost"
            self._refresh()
            raise
        return view

    def check_stop(self) -> None:
        """Ctrl-C is deferred to here (see ``request_stop``): between writes, never inside one."""
        if self.stop_requested:
            raise KeyboardInterrupt

    def request_stop(self) -> None:
        """Called by the SIGINT handler: the loop stops at its next safe point; a second press
        while stopping raises at once."""
        if self.stop_requested:
            raise KeyboardInterrupt
        self.stop_requested = True

    def fail(self, why: str) -> None:
        """A failure mid-job (not a lost port): stop at the next safe point, like Ctrl-C, and
        let the summary say ``why``."""
        self.failure = self.failure or why
        self.stop_requested = True

    def _step(self) -> None:
        self.check_stop()
        self._drain()
        if self.link.error is not None:
            raise self.link.error
        now = self.now()
        when = self.streamer.next_write_time(now, self.view.next_statement.command)
        self._explain_wait(now, when)
        if when is not None and when <= now:
            self._write(self.view.next_statement, now)
            self._refresh()  # only after every record of the write is complete
        else:
            self._refresh()
            self._sleep(POLL_S if when is None else min(when - now, POLL_S))

    def _write(self, statement, now: float) -> None:
        """Write one frame and record it everywhere; nothing here calls out (no display)."""
        command = statement.command
        frame = command.encode()
        self.link.write(frame)
        sent = self.streamer.wrote(command, now, tag=statement)
        self._recent.append(sent)
        view = self.view
        view.frames_sent += 1
        view.last_sent = statement
        view.next_statement = next(self.statements, None)
        view.remaining_motion_s = max(0.0, view.remaining_motion_s - sent.segment.duration_s)
        if self.log is not None:
            self._log("tx", frame, now, line=statement.line)

    def _refresh(self) -> None:
        view, streamer = self.view, self.streamer
        view.now_s = self.now()
        view.queued_frames_bound = streamer.frames_in_flight_bound
        view.queued_s = streamer.queued_seconds(view.now_s)
        view.last_done = streamer.last_known_done()
        view.first_not_done = self._first_not_done()
        self.on_update(view)

    def _first_not_done(self):
        pending = self.streamer.pending
        if not pending:
            return self.view.next_statement
        if isinstance(pending[0].command, ArcEnd) and self.view.last_done is not None:
            return self.view.last_done  # a G301 cannot be resumed alone: resume at its G300
        return pending[0].tag

    # --- the end ----------------------------------------------------------------------------

    def arm_at_rest(self, now: float) -> bool:
        """The arm reported the same position, joints and PWM for REST_CHECK_S and the estimate
        says the job is over."""
        finish = self.streamer.estimated_finish_s()
        if finish is not None and now < finish:
            return False
        if self._active_s is not None and now - self._active_s < REST_CHECK_S:
            return False  # an SD program still advancing, even with the arm standing still
        return self._rest is not None and now - self._rest[1] >= REST_CHECK_S

    @property
    def arm_paused(self) -> bool | None:
        """The pause state when the last two pause reports agree (one corrupted byte must not
        make armctl toggle the arm); None while they disagree or are missing."""
        reports = self._pause_reports
        if len(reports) == 2 and reports[0] == reports[1]:
            return reports[0]
        return None

    def _at_last_target(self) -> bool:
        """The arm reports the end of the last frame written (joints for a joint move)."""
        if not self._recent:
            return True
        segment = self._recent[-1].segment
        if segment.kind == "joint":
            joints = (self._reported.get(1) or ()) + (self._reported.get(2) or ())
            return len(joints) == 6 and max(abs(a - b) for a, b in zip(joints, segment.end.joints)) <= TARGET_DEG
        position = self._reported.get(0)
        return position is not None and max(abs(a - b) for a, b in zip(position, segment.end.xyz)) <= TARGET_MM

    def _done_at(self, now: float) -> float:
        """When the arm finished: the end of its last motion seen, plus the model's time for
        the frames after that motion, which move nothing (delays, M codes, control frames,
        PWM-only moves, a move to where the arm already is); never before the last change
        seen at all (a PWM report), never after now."""
        if self._motion is None:  # set with _rest: nothing reported yet
            return now
        done = self._motion[1]
        for sent in reversed(self._recent):
            if _moves_arm(sent.segment):
                break
            done += sent.segment.duration_s
        return min(max(done, self._rest[1], self._active_s or 0.0), now)

    def _wait_for_finish(self) -> None:
        """Finished means: at rest, at the last target, not paused, and the estimate agrees.
        Anything else ends without claiming the job ran (frames cleared or dropped, a pause)."""
        view = self.view
        now = self.now()
        deadline = now + self.streamer.queued_seconds(now) * self.streamer.slowest_factor + SETTLE_SLACK_S
        overran = False
        while True:
            self.check_stop()
            self._drain()
            if self.link.error is not None:
                raise self.link.error
            now = self.now()
            if self.arm_at_rest(now) and self._at_last_target() and self.arm_paused is False:
                self._confirm_all_done(now)
                view.arm_done_s = self._done_at(now)
                view.outcome = "finished"
                if overran:
                    view.messages.append("the arm kept working past the estimate (moving, or running an SD program "
                                         "whose time armctl cannot know); armctl waited until it stopped")
                break
            if now > deadline:
                # Visibly working: the job is still running, whatever the estimate says; once it
                # stops, there is time to confirm it is where the job ends.
                overran = overran or (self._active_s is not None and now - self._active_s < REST_CHECK_S)
                settling = overran and now - self._active_s < REST_CHECK_S + SETTLE_SLACK_S
                if not settling or now > deadline + self._overrun_limit_s():
                    view.outcome = "no confirmation"
                    view.messages.append(self._why_not_finished())
                    break
            self._refresh()
            self._sleep(POLL_S)
        self._refresh()

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
            target = ", ".join(f"{v:.1f}" for v in self._recent[-1].segment.end.xyz)
            here = ", ".join(f"{v:.1f}" for v in position)
            return (f"the arm stopped at ({here}) but the job's last target is ({target}): "
                    "frames were lost or cleared (a RESET CONNECTOR, a full buffer?)")
        return "the arm did not confirm the end of the job in time (status frames missing?)"

    def abort(self, sequence: tuple) -> None:
        """Ctrl-C: stop feeding (nothing more is written after this call), send the abort
        sequence, and wait for the arm to come to rest so the view can say what ran.
        A pause toggle is not sent to an arm that reports it is paused: it would resume it."""
        view = self.view
        view.outcome = "interrupted"
        self._drain()
        if self.arm_paused and any(isinstance(c, PauseToggle) for c in sequence):
            view.messages.append("the arm was already paused: no pause toggle sent (it would have resumed it)")
            sequence = tuple(c for c in sequence if not isinstance(c, PauseToggle))
        for command in sequence:
            frame = command.encode()
            try:
                self.link.write(frame)
            except PortError as error:
                view.outcome = "port lost"
                view.messages.append(f"the abort sequence was NOT sent: {error}")
                return
            if self.log is not None:
                self._log("tx", frame, self.now(), abort=True)
        deadline = self.now() + self.streamer.queued_seconds(self.now()) * self.streamer.slowest_factor + SETTLE_SLACK_S
        while self.now() < deadline:
            self._drain()
            if self.link.error is not None:
                view.outcome = "port lost"
                view.messages.append(str(self.link.error))
                break
            now = self.now()
            still = self._rest is not None and now - self._rest[1] >= REST_CHECK_S
            # At rest: paused (the estimate cannot know for how long) or with the job's time over.
            if still and (self.arm_paused or self.arm_at_rest(now)):
                if self._at_last_target():
                    self._confirm_all_done(now)
                break
            self._refresh()
            self._sleep(POLL_S)
        self._refresh()

    def _confirm_all_done(self, now: float) -> None:
        self.streamer.confirm_all_done()
        self._explain_bound(now)

    # --- -v: the pacing story ---------------------------------------------------------------

    def _explain_wait(self, now: float, when: float | None) -> None:
        """Log why the next write waits, when the reason differs from the last one logged."""
        reason = self.streamer.write_reason
        if reason is WaitReason.READY or not _logger.isEnabledFor(logging.INFO):
            return
        if reason is not WaitReason.WIRE:
            self._wire_frames = 0
        elif self._wire_counted_at != self.view.frames_sent:
            self._wire_frames += 1
            self._wire_counted_at = self.view.frames_sent
        if reason is self._told_wait or (reason is WaitReason.WIRE and self._wire_frames < WIRE_STORY_FRAMES):
            return
        self._told_wait = reason
        streamer, line = self.streamer, self.view.next_statement.line
        if reason is WaitReason.CAPACITY:
            why = (f"the FIFO's capacity: {streamer.frames_in_flight_bound} frames written and not known consumed, "
                   f"the bound is {streamer.limit_frames} (the connector's FIFO less a margin); only new evidence "
                   "that frames finished lets it go")
        elif reason is WaitReason.LEAD:
            why = (f"the lead: {streamer.waiting_seconds(now):.2f} s of motion waits behind the move in progress "
                   f"and this frame adds {streamer.next_frame_motion_s:.2f} s (lead {streamer.lead_s:g} s); "
                   f"it may go in {when - now:.2f} s")
        else:
            why = (f"the wire: the last {WIRE_STORY_FRAMES} frames waited only for the frame before to leave at "
                   f"the line's rate ({streamer.frame_s * 1000:.0f} ms a frame): the job is line-bound here")
        _logger.info("t=%.2f s: line %s waits for %s", now - self.view.started_s, line, why)

    def _explain_bound(self, now: float) -> None:
        """Log what advanced the lower bound of frames consumed, when the kind of evidence changes."""
        evidence = self.streamer.bound_evidence
        if evidence is None or evidence is self._told_evidence or not _logger.isEnabledFor(logging.INFO):
            return
        self._told_evidence = evidence
        streamer = self.streamer
        done = streamer.last_known_done()
        how = {
            Evidence.POSITION: "two agreeing position reports lie on the path of a later frame",
            Evidence.JOINTS: "two agreeing joint reports lie on the path of a later frame",
            Evidence.TIME: f"even an arm {streamer.slowest_factor:g}x slower than the model has finished them "
                           "(time the arm was seen running)",
            Evidence.AT_REST: "the arm is at rest at the last target",
        }[evidence]
        _logger.info("t=%.2f s: evidence (%s): %s; frames known consumed: %d, through line %s",
                     now - self.view.started_s, evidence, how, streamer.consumed_lower_bound,
                     getattr(done, "line", "?"))

    def _log(self, direction: str, frame: bytes, at_s: float, **extra) -> None:
        """One JSON line; a log that cannot be written (disk full, EIO) stops the job (``fail``):
        the record of what was sent is part of the job."""
        self.log_record({"t": round(at_s, 4), "dir": direction, "hex": frame.hex(), **extra})

    def log_record(self, record: dict) -> None:
        """One JSON line in the --log (a frame, or a job record of armctl/joblog.py)."""
        if self.log is None:
            return
        try:
            self.log.write(json.dumps(record) + "\n")
        except (OSError, ValueError) as error:  # ValueError: the file was closed under us
            name = getattr(self.log, "name", "the log")
            self.log = None  # nothing more is written to it (the abort is not logged)
            self.fail(f"the log {name} could not be written ({error})")


def _moves_arm(segment) -> bool:
    """Whether a frame's motion changes the reported position or joints."""
    if segment.kind == "still":
        return False
    if segment.length > 0:
        return True
    return max(abs(a - b) for a, b in zip(segment.start.joints, segment.end.joints)) > 1e-6  # attitude only


def _moved_clearly(before: tuple, after: tuple) -> bool:
    """Position (kind 0) or joints (kinds 1, 2) changed by more than a reading's jitter."""
    for kind, (old, new) in enumerate(zip(before, after)):
        if old is None or new is None:
            if old is not new:
                return True
            continue
        limit = TARGET_MM if kind == 0 else TARGET_DEG
        if max(abs(a - b) for a, b in zip(old, new)) > limit:
            return True
    return False
