"""``armctl run``'s host: the pure job engine (armctl/core/job.py) driven against an open Link.

Strategy: the edge where time is real.  The engine holds every rule of a job — pacing through
the streamer, when it is over, how it stops, where to resume; the one host driver
(armctl/host/driver.py) carries out what it asks — write, wait, stop — and this module is the job's
``Host``: before each action the stop asked for and the status frames read meanwhile (the
link's reader thread queues them, ``on_status``; the panel's requests first), before a write the
--log record made durable (a frame without one does not go), after it ``Job.wrote`` and the
panel.  Time is the link's one ``Clock``: on the wall a wait is capped at ``POLL_S`` so Ctrl-C
and the panel stay prompt, the next frame may be handed to the port up to ``WRITE_AHEAD_S``
before the line is free (a late wake-up then never idles the line) and the port's own unsent
bytes push its start back (``Link.unsent_s``); on a virtual clock the link hands the frames to
``take_statuses`` as it reads them, and the wait jumps from burst to burst until a frame is news
to the engine (``Job.receive_statuses``), a request or a stop is queued, or the engine's own
next time comes: a virtual job costs its status frames, and a turn of the loop only for a frame
that can change the next action (``benchmarks/virtual_run.py`` measures it against the bare
simulator).  Either way the engine takes status frames one way: ``Job.receive_statuses``.

Every ending — finished, Ctrl-C, a lost port, a failure such as a --log that cannot be written —
leaves a ``RunView`` that says the last line sent, the last line known executed and where to
resume.  A failure the runner meets itself (``fail``) takes the Ctrl-C path: it asks to stop at
the next safe point, and the caller sends the abort sequence (``abort``).  With ``-v`` it tells
the pacing story (armctl/host/pacing_story.py).
"""

from __future__ import annotations

import json
import queue
from typing import Callable, Iterator

from .driver import Host, drive
from ..errors import ArmctlError, PortError
from .link import WRITE_AHEAD_S
from ..core.job import Job, RunView, Wait, Write
from .pacing_story import PacingStory, telling
from ..core.protocol import StatusFrame
from ..core.streamer import Streamer

POLL_S = 0.05  # the longest wait on a wall clock (model seconds): Ctrl-C and the panel stay prompt


class Aborted(ArmctlError):
    """The user stopped the job (Ctrl-C); the view says where."""


class JobRunner(Host):
    """Streams compiled statements through ``link`` with ``streamer``'s pacing (a ``Job``)."""

    def __init__(
        self,
        link,
        streamer: Streamer,
        statements: Iterator,
        view: RunView,
        *,
        clock: Callable[[], float] | None = None,
        log=None,
        on_update: Callable[[RunView], None] | None = None,
        pacing=None,
        fifo_proven: bool = True,
        control_frames_proven: bool = True,
    ) -> None:
        self.link = link
        self.streamer = streamer
        self.view = view
        self.job = Job(streamer, statements, view, pacing=pacing, fifo_proven=fifo_proven,
                       control_frames_proven=control_frames_proven)
        self.clock = link.clock if clock is None else clock
        self._virtual = getattr(self.clock, "virtual", False)
        self._origin_s = self.clock()  # model seconds count from here (the log's t)
        self.log = log
        # the journal's fields of a job frame's record: (n, statement, planned segment) → dict
        self.frame_fields: Callable[[int, object, object], dict] | None = None
        # called once, durable before the job's first frame goes (a resume marks the log it continues)
        self.before_first_frame: Callable[[], None] | None = None
        self.on_update = on_update or (lambda view: None)
        self.status_queue: queue.SimpleQueue = queue.SimpleQueue()
        self.requests: queue.SimpleQueue = queue.SimpleQueue()  # ``control``: calls for the engine, from any thread
        self.stop_requested = False
        self._aborting = False
        self._cut = False  # cut_short: the abort's wait for the arm ends at the next turn
        self.story = PacingStory(streamer, view)
        # Nothing to tell for a frame (no --log, -v's logger quiet): read at each wait, so a
        # virtual-time frame costs no logging call (``take_statuses``)
        self._quiet = False
        self._job_receive = self.job.receive_statuses
        self.news = self.take_statuses if self._virtual else None
        if not self._virtual:  # (a virtual clock is never late: its writes go at the line's instant)
            streamer.write_ahead_s = max(streamer.write_ahead_s, WRITE_AHEAD_S)

    @property
    def failure(self) -> str | None:
        """Why the job stopped, when not by Ctrl-C (``fail``)."""
        return self.job.failure

    @failure.setter
    def failure(self, why: str | None) -> None:
        self.job.failure = why

    @property
    def arm_paused(self) -> bool | None:
        return self.job.arm_paused

    # --- time and status --------------------------------------------------------------------

    def now(self, clock=None) -> float:
        """Model seconds since the runner was made (the link's clock)."""
        return self.clock() - self._origin_s

    def on_status(self, frame: StatusFrame, read_s: float) -> None:
        """Called by the link's reader thread (a wall clock) with each frame and the model time
        it was read: queued for the loop's next turn."""
        self.status_queue.put((frame, read_s - self._origin_s))

    def take_statuses(self, frames: list, times: list) -> int | None:
        """A virtual wait's frames (``Host.news``), read at the model time at the same place of
        ``times``, in order: the place of the first that is news — it may change the engine's
        next action, a request is queued or a stop asked (the frames after it are not taken) —
        or None when the link may read on past them all.  With nothing to tell (no --log, -v
        quiet) and no request queued, the engine takes them in one call; a stop asked meanwhile
        is seen after them (they are a batch of the simulator's quiet frames)."""
        origin_s = self._origin_s
        if not self._quiet or self.stop_requested or not self.requests.empty():
            for k, frame in enumerate(frames):
                if self._take_one(frame, times[k] - origin_s):
                    return k
            return None
        news = self._job_receive(frames, [t - origin_s for t in times] if origin_s else times)
        if news is None and (self.stop_requested or not self.requests.empty()):
            return len(frames) - 1
        return news

    def _take_one(self, frame: StatusFrame, at_s: float) -> bool:
        """One frame of a virtual wait into the engine (the requests queued before it first, as
        ``turn`` orders them); whether it ends the wait."""
        requests = self.requests
        if not requests.empty():
            while not requests.empty():
                requests.get_nowait()(self.job)
            self._receive(frame, at_s)
            return True  # the engine's answer after a request is news
        if self._quiet:  # _receive with nothing to tell (the log level as it was when the wait began)
            news = self._job_receive((frame,), (at_s,)) is not None
        else:
            news = self._receive(frame, at_s)
        return news or self.stop_requested or not requests.empty()

    def control(self, request: Callable[[Job], object]) -> None:
        """Queue ``request(job)`` (e.g. ``Job.pause``) from any thread — the run panel's keys;
        the loop carries it out at its next turn, between writes (within ``POLL_S``)."""
        self.requests.put(request)

    def _receive(self, frame: StatusFrame, at_s: float) -> bool:
        """One status frame into the engine (and -v's story, the --log); whether it was news."""
        news = self._job_receive((frame,), (at_s,)) is not None
        if telling():
            self.story.bound(at_s)  # the streamer names new evidence only when the bound moved
        if self.log is not None:
            self._log("rx", frame.encode(), at_s, kind=frame.KIND)
        return news

    # --- the job: the driver's hooks --------------------------------------------------------

    def run(self) -> RunView:
        """Stream every statement, then wait for the arm to finish. Raises KeyboardInterrupt
        at the first safe point after a stop was asked for (then call ``abort``), or
        PortError (after updating the view)."""
        try:
            drive(self.job, self.link, self)
        except PortError:
            self.job.port_lost()
            self.on_update(self.view)
            raise
        return self.view

    def turn(self) -> None:
        if self.stop_requested and (self._cut or not self._aborting):
            raise KeyboardInterrupt  # Ctrl-C is deferred to here: between writes, never inside one
        self._drain()

    def _drain(self) -> None:
        requests = self.requests
        while not requests.empty():  # the panel's keys first: their effect shows in this turn
            requests.get_nowait()(self.job)
        status_queue = self.status_queue
        while not status_queue.empty():
            try:
                frame, at_s = status_queue.get_nowait()
            except queue.Empty:
                return
            self._receive(frame, at_s)

    def writing(self, action: Write, now: float) -> bool:
        if self.log is not None and not self._log_write(action, now):
            return False  # no durable record, no frame: the failure stops the job (``fail``)
        if self.before_first_frame is not None and action.statement is not None:
            mark, self.before_first_frame = self.before_first_frame, None
            try:
                mark()
            except OSError as error:  # as a log that cannot be written: the frame must not go
                self.fail(f"the log --resume continues could not be marked resumed ({error}): nothing of the job was sent")
                return False
        if not self._virtual:
            self._note_unsent(now)
        return True

    def wrote(self, action: Write, now: float) -> None:
        self.job.wrote(now)
        self.on_update(self.view)  # only after every record of the write is complete

    def waiting(self, action: Wait, now: float) -> float | None:
        if self.job.streaming:
            self.story.wait(now, action.until_s)
        self.on_update(self.view)
        until_s = action.until_s
        if not self._virtual:  # a wall clock: wake at least every POLL_S (Ctrl-C, the panel)
            until_s = now + POLL_S if until_s is None else min(until_s, now + POLL_S)
        self._quiet = self.log is None and not telling()
        return None if until_s is None else until_s + self._origin_s

    def done(self, action, now: float) -> None:
        self.story.bound(now)  # the arm at rest at the last target
        self.on_update(self.view)

    def _note_unsent(self, now: float) -> None:
        """Before a write on a wall clock: what the port still holds leaves first, so the frame
        lands no earlier than that (``Link.unsent_s``; the streamer's line model is the floor)."""
        unsent = getattr(self.link, "unsent_s", None)  # (a stand-in link in a test may not say)
        unsent_s = unsent() if unsent is not None else None
        if unsent_s:
            self.streamer.line_busy_until(now + unsent_s)

    def check_stop(self) -> None:
        """Ctrl-C is deferred to the loop's safe point (see ``request_stop``)."""
        if self.stop_requested:
            raise KeyboardInterrupt

    def request_stop(self) -> None:
        """Called by the SIGINT handler: the loop stops at its next safe point; a second press
        while stopping raises at once."""
        if self.stop_requested:
            raise KeyboardInterrupt
        self.stop_requested = True

    def cut_short(self) -> None:
        """A second stop from another thread (``Arm.stop`` again): once the abort has begun, it
        stops waiting for the arm at the loop's next turn, as a second Ctrl-C does in the loop's
        own thread; before that it is the first stop again (the abort sequence always goes)."""
        if self._aborting:
            self._cut = True

    def fail(self, why: str) -> None:
        """A failure mid-job (not a lost port): stop at the next safe point, like Ctrl-C, and
        let the summary say ``why``."""
        self.job.failure = self.job.failure or why
        self.stop_requested = True

    def abort(self, sequence: tuple) -> None:
        """After ``run`` stopped (Ctrl-C, a failure): nothing more of the job is written; the
        engine sends ``sequence`` (no pause toggle to an arm that reports it is paused: it
        would resume it) and waits for the arm to come to rest, so the view can say what ran."""
        job = self.job
        job.abort_sequence = tuple(sequence)
        job.request_stop()
        self._aborting = self.stop_requested = True
        try:
            drive(job, self.link, self)
        except PortError as error:
            job.port_lost(f"the abort sequence was NOT sent: {error}" if job.aborting else str(error))
            self.on_update(self.view)

    # --- the --log --------------------------------------------------------------------------

    def _log(self, direction: str, frame: bytes, at_s: float, **extra) -> None:
        """One JSON line; a log that cannot be written (disk full, EIO) stops the job (``fail``):
        the record of what was sent is part of the job."""
        self.log_record({"t": round(at_s, 4), "dir": direction, "hex": frame.hex(), **extra})

    def _log_write(self, action: Write, now: float) -> bool:
        """The record of the frame ``action`` writes, durable (flushed, fsynced) before the frame
        goes to the port: the journal is a write-ahead log (armctl/core/joblog.py).  A job frame's
        record carries what ``frame_fields`` adds (its number, lines, target).  False when it
        could not be written: then the frame must not be either."""
        if action.control is not None:
            extra = {"control": action.control}
        elif action.statement is None:
            extra = {"abort": True}
        else:
            extra = {"line": action.statement.line}
            if self.frame_fields is not None:
                command = getattr(self.job, "_command", None)
                segment = self.streamer.plan(command) if command is not None else None  # the planner's, kept for wrote
                extra.update(self.frame_fields(self.view.frames_sent + 1, action.statement, segment))
        self.log_record({"t": round(now, 4), "dir": "tx", "hex": action.frame.hex(), **extra}, durable=True)
        return self.log is not None

    def log_record(self, record: dict, durable: bool = False) -> None:
        """One sealed JSON line in the --log (a frame, or a job record of armctl/core/joblog.py);
        ``durable``: flushed and fsynced before this returns (a frame's record, before the frame)."""
        if self.log is None:
            return
        try:
            append = getattr(self.log, "append", None)
            if append is not None:  # a jobflow.JournalFile: it seals and syncs
                append(record, durable)
            else:
                self.log.write(json.dumps(record) + "\n")
        except (OSError, ValueError) as error:  # ValueError: the file was closed under us
            name = getattr(self.log, "name", "the log")
            self.log = None  # nothing more is written to it (the abort is not logged)
            self.fail(f"the log {name} could not be written ({error})")
