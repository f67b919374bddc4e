"""Stopping a job: the abort sequence, then the arm's rest — and what the next run sends first.

Strategy: pure; ``Stop`` owns the abort frames still to write and decides, from the arm's
reports (armctl/core/job_readings.py) and where it rests (armctl/core/job_arrival.py), when a stopped job
is over and what its reports prove ran.  What it may conclude, from what evidence:

- Nothing more of the job is written once a stop is asked (Ctrl-C, a failure the host met);
  the abort sequence goes instead — minus a pause toggle to an arm that reports it is paused
  (two agreeing reports), or to which a pause is already on its way, or that the script's own
  PAUSE paused: a toggle would resume it.  The control mode shapes the sequence and the start
  of the next run (``abort_frames``, ``resume_frames``), so an abort and its resume line run
  every line once.
- Nothing to stop: a stop before the job's first frame (and no pause of the user's on its way)
  finds nothing of the job queued: no abort sequence goes, the job ends at once and the arm is
  left as it was (a pause toggle would leave it paused, a RESET CONNECTOR clear another's queue).
- Settling: the job ends INTERRUPTED (FAILED with a failure) once the arm is still
  (armctl/core/evidence.py's rest) and paused, or at rest with the job's time over — or at the
  deadline.  Paused on an arm that acts on control frames as they land, only the moves whose
  ends it reached ran (``Arrival.confirm_through_last_move``); at the last target otherwise,
  every frame written ran.
- An arm profiled as queueing its control frames (H5) that froze mid-move has shown they act as
  they land (``Arrival.frozen_mid_move``): a RESET CONNECTOR then clears what is still queued,
  so the resume runs nothing twice.
"""

from __future__ import annotations

from collections import deque

from .evidence import REST_CHECK_S
from .job_end import Outcome
from .protocol import PauseToggle, ResetConnector

NOTHING_SENT = "stopped before the first frame: nothing was sent, the arm is left as it was"

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


class Stop:
    """The stop of one job: the abort frames still to write, and the settling after them."""

    def __init__(self, view, control, end) -> None:
        self.view = view
        self.control = control
        self.end = end
        self.arrival = end.arrival
        self.readings = end.readings
        self.written = end.written
        self.streamer = end.streamer
        self.frames: deque = deque()  # abort frames still to write
        self.needless = False  # begun with nothing of the job written: nothing to stop, nothing to wait for

    @property
    def nothing_to_stop(self) -> bool:
        """Nothing of the job was written and no pause toggle of the user's is due or on its way:
        nothing the job sent is queued, so a stop sends no abort sequence and waits for nothing."""
        return self.view.frames_sent == 0 and not self.control.busy

    def begin(self, sequence: tuple) -> None:
        """Nothing more of the job is written; the abort ``sequence`` goes instead — none when there
        is nothing to stop.  A pause toggle is not sent to an arm that reports it is paused: it
        would resume it."""
        view, control, written = self.view, self.control, self.written
        view.outcome = Outcome.INTERRUPTED
        if self.nothing_to_stop:
            self.needless = True
            view.messages.append(NOTHING_SENT)
            return
        if self.streamer.control_on_arrival and sequence == abort_frames("pause", True):
            view.messages.append("the arm acts on control frames as they land: the pause froze the move in progress "
                                 "and a RESET CONNECTOR cleared the frames queued behind it; the resume command resumes "
                                 "that move, then re-sends its line (an absolute move to where the arm then is)")
        paused = self.readings.paused
        control.observe(paused)
        script_pause = written.script_paused  # the script's own PAUSE pauses (or paused) it
        if (script_pause or not control.abort_needs_toggle()) and any(isinstance(c, PauseToggle) for c in sequence):
            why = (f"the script's PAUSE at line {written.script_pause_line()} was already written"
                   if script_pause and paused is not True
                   else "a pause was already on its way" if control.state == "pausing"
                   else "the arm was already paused")
            view.messages.append(f"{why}: no pause toggle sent (it would have resumed it)")
            sequence = tuple(c for c in sequence if not isinstance(c, PauseToggle))
        self.frames = deque(sequence)

    def wrote(self) -> None:
        """The host wrote the first abort frame."""
        if isinstance(self.frames.popleft(), ResetConnector) and self.arrival.acts_on_arrival:
            self.streamer.cleared()  # it acted as it landed: what was queued may be gone

    def settle(self, now: float, failure: str | None) -> Outcome | float | None:
        """After the abort sequence: the outcome once the arm is at rest — paused (the estimate
        cannot know for how long) or with the job's time over — or at the deadline; else the time
        to wait until; None when a RESET CONNECTOR is to go first (``paused_on_arrival``)."""
        outcome = Outcome.FAILED if failure else Outcome.INTERRUPTED
        end, arrival = self.end, self.arrival
        if now >= end.deadline_s or self.needless:
            return outcome
        still = self.readings.rest_s() >= REST_CHECK_S
        paused = self.readings.paused
        if still and (paused or arrival.arm_at_rest(now)):
            if paused and not arrival.acts_on_arrival and self.paused_on_arrival():
                return None  # the RESET CONNECTOR that clears what is still queued
            if paused and arrival.acts_on_arrival:
                # The pause acted as it landed: the arm at the last target says nothing of the frames
                # after its last move (a PWM change, a delay: the RESET CONNECTOR cleared them, or
                # not); the moves it reached the ends of did run.
                arrival.settle_paused()
            elif arrival.at_last_target():
                self.streamer.confirm_all_done()
            return outcome
        return end.next_change_s(now, end.deadline_s)

    def paused_on_arrival(self) -> bool:
        """On an arm the profile says queues its control frames (H5), the abort's pause acted as it
        landed — the arm paused with frames still queued behind it, which the next run's toggle
        would release to run before its resume line re-sends them: then a RESET CONNECTOR goes
        (it acts as it lands too, on such an arm) and True.  Proven only by the arm frozen
        mid-move (``Arrival.frozen_mid_move``: a queued pause acts only between frames): on a
        queued arm the same RESET CONNECTOR would wait at the head of its paused FIFO for ever,
        and a pause that merely came sooner than the queue could run is what a FIFO that dropped
        frames shows too.  (Frozen in a frame that moves nothing — a PWM change, a delay — such
        an arm shows nothing: `armctl probe` measures the mode.)"""
        if self.frames or not self.arrival.proves_arrival():
            return False
        self.view.messages.append(
            "the arm paused mid-move with frames still queued: its control frames act as they land, though the "
            "profile says they queue (run `armctl probe`); a RESET CONNECTOR cleared the queue, so the resume runs "
            "nothing twice")
        self.frames.append(ResetConnector())
        return True
