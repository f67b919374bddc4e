"""Control of a running job: pause, resume and the feed override, as a pure state machine —
and the pause rule, once, for everything that sends a pause toggle.

The rule: the toggle flips the arm between running and paused, so it is sent to reach a state
only when the arm is known to be in the other one, and one corrupted status byte must not
decide that — the arm's state counts as known when its last two pause reports agree
(``agreed_pause``: armctl/core/evidence.py's rule of agreeing reports); ``pause_toggle_needed`` is the
one decision.  ``armctl run``'s start
(armctl/host/jobflow.py: resume an arm that reports it is paused), the engine's pause, resume and
abort (``JobControl``, below) and ``armctl.Arm`` on an idle arm all ask it.  A toggle sent and
not yet acted on is ``JobControl``'s "pausing…"/"resuming…" state.

Strategy: the user asks (``pause``, ``resume``, ``toggle``, ``set_feed_override``); the job
engine asks back — is a pause toggle due to be written (``take_toggle``), may frames be
written (``holds_feed``), which command goes out for a statement (``command_for``: the feed
override applied, armctl/core/feed.py) — and feeds in the arm's pause state as the engine's
twice-agreeing kind-4 rule decides it (``observe``).  No clock, no I/O.

Pause is the protocol's pause toggle (control 30/3) plus holding the feed: nothing more is
written from the moment a pause is asked until a resume.  Both control-frame modes (H5):

- ``queued`` — the toggle waits in the FIFO behind what is queued, so the arm pauses once it
  has run that (at most the lead plus the move in progress); the panel says "pausing…" until
  the arm reports paused.  The FIFO is empty by then, so the resume toggle is at its head.
- ``arrival`` — the toggle acts when it lands: the arm freezes mid-move with frames still
  queued; the resume toggle acts when it lands too.  The engine writes toggles without asking
  the streamer's capacity or lead (only the wire), so a resume is never held behind a FIFO
  the streamer counts as full.

What the panel shows follows the arm's reports, not the keys: "pausing…" (asked, the arm still
runs), "paused" (the arm says so), "resuming…" (the resume toggle is written, the arm still
says paused), "running".  A pause the job itself caused (a ``PAUSE`` line) shows as "paused
(by the job)" and is left to the job.  The abort (Ctrl-C, ``s``) asks ``abort_needs_toggle``:
a pause toggle is not sent when one is already on its way or the arm is paused — it would
undo the pause.
"""

from __future__ import annotations

from enum import StrEnum

from .evidence import agreed
from .feed import FeedOverride
from .profile_model import CONTROL_FRAMES

# The pause state when the last two pause reports agree (one corrupted byte must not make armctl
# toggle the arm); None while they disagree or fewer than two were read: armctl/core/evidence.py's rule
# of agreeing reports, named for the pause reports.
agreed_pause = agreed


def pause_toggle_needed(want_paused: bool, agreed: bool | None) -> bool | None:
    """Whether to send the pause toggle so the arm ends ``want_paused``: True only when two
    agreeing reports say it is in the other state, False when they say it already is; None
    while the state is not known (a toggle on a guess may do the opposite: read again)."""
    if agreed is None:
        return None
    return agreed != want_paused


def control_frames_of(profile) -> str:
    """The arm's control-frame mode (H5): the profile's ``connector.control_frames`` — the one
    place the job's control reads it."""
    return profile.connector.control_frames


class PauseState(StrEnum):
    RUNNING = "running"
    PAUSING = "pausing"
    PAUSED = "paused"
    RESUMING = "resuming"


LABELS = {PauseState.RUNNING: "running", PauseState.PAUSING: "pausing…", PauseState.PAUSED: "paused",
          PauseState.RESUMING: "resuming…"}


class JobControl:
    """The user's control of one job; ``speed_limits`` is the profile's ``Speeds``."""

    def __init__(self, speed_limits, control_frames: str = "queued") -> None:
        if control_frames not in CONTROL_FRAMES:
            raise ValueError(f"control_frames must be one of {CONTROL_FRAMES}, not {control_frames!r}")
        self.control_frames = control_frames
        self.feed = FeedOverride(speed_limits)
        self.state = PauseState.RUNNING
        self.arm_paused: bool | None = None  # the engine's twice-agreeing reading
        self._toggles_due = 0
        # A toggle is due or a pause is asked or in force: the engine has something to do here
        # (a plain attribute, kept by ``_note_busy`` at each change: read for every status frame).
        self.busy = False
        self._scaled: tuple | None = None  # (statement, percent, command): planned once, written the same
        self.version = 0  # grows whenever anything a view shows changes (the engine copies it then)

    # --- asked by the user ---------------------------------------------------------------------

    def pause(self) -> bool:
        """Ask for a pause; False when there is nothing to pause (pausing, paused, or the arm
        reports it is paused already)."""
        if self.state is not PauseState.RUNNING or pause_toggle_needed(True, self.arm_paused) is False:
            return False  # a toggle to an arm that reports it is paused would resume it
        # (reports that disagree do not refuse it: the job started from a running arm, and the
        # feed is held from now on whatever the arm does)
        self.state = PauseState.PAUSING
        self._toggles_due += 1
        self.version += 1
        self._note_busy()
        return True

    def resume(self) -> bool:
        """Ask for a resume (of a pause asked here); False when not paused or pausing."""
        if self.state not in (PauseState.PAUSING, PauseState.PAUSED):
            return False
        self.state = PauseState.RESUMING
        self._toggles_due += 1
        self.version += 1
        self._note_busy()
        return True

    def toggle(self) -> bool:
        return self.pause() if self.state is PauseState.RUNNING else self.resume()

    def set_feed_override(self, percent: int) -> int:
        """The new override, on the 10 % grid within 10…200 % (frames not yet written)."""
        self.version += 1
        return self.feed.set_percent(percent)

    def step_feed_override(self, steps: int) -> int:
        self.version += 1
        return self.feed.step(steps)

    # --- asked by the engine ------------------------------------------------------------------

    def observe(self, arm_paused: bool | None) -> None:
        """The arm's pause state as the engine reads it (None: the last two reports disagree)."""
        if arm_paused is not self.arm_paused:
            self.arm_paused = arm_paused
            self.version += 1
        if self.state is PauseState.PAUSING and arm_paused is True:
            self.state = PauseState.PAUSED
            self.version += 1
        elif self.state is PauseState.RESUMING and arm_paused is False and not self._toggles_due:
            self.state = PauseState.RUNNING
            self.version += 1
            self._note_busy()

    def take_toggle(self) -> bool:
        """Whether a pause toggle is to be written now; the engine writes it (wire permitting)."""
        if not self._toggles_due:
            return False
        self._toggles_due -= 1
        self.version += 1
        self._note_busy()
        return True

    def _note_busy(self) -> None:
        """``busy`` after a change of the pause state or of the toggles due."""
        self.busy = self._toggles_due > 0 or self.state is not PauseState.RUNNING

    @property
    def toggle_due(self) -> bool:
        return self._toggles_due > 0

    @property
    def holds_feed(self) -> bool:
        """No statement is written while a pause is asked or in force (a resume's toggle goes
        first, then the frames behind it)."""
        return self.state in (PauseState.PAUSING, PauseState.PAUSED) or self._toggles_due > 0

    @property
    def user_paused(self) -> bool:
        """A pause asked here is on its way or in force: the end of the job waits for it."""
        return self.state is not PauseState.RUNNING

    def abort_needs_toggle(self) -> bool:
        """Whether the abort's pause toggle should go: not when a pause is on its way or the
        arm is paused (it would resume it); yes after a resume toggle (the arm would run on)."""
        if self.state is PauseState.RESUMING:
            return True
        return self.state is PauseState.RUNNING and pause_toggle_needed(True, self.arm_paused) is not False

    def planned_for(self, statement) -> bool:
        """Whether ``command_for(statement)`` has its command already (it then changes nothing)."""
        cached = self._scaled
        return cached is not None and cached[0] is statement and cached[1] == self.feed.percent

    def command_for(self, statement):
        """The command to plan and write for ``statement``: the override applied once per
        statement and percentage, so the streamer plans exactly what is written."""
        if not self.planned_for(statement):
            feed = self.feed
            clamped = feed.clamped
            self._scaled = (statement, feed.percent, feed.apply(statement.command))
            if feed.clamped is not clamped:
                self.version += 1
        return self._scaled[2]

    @property
    def label(self) -> str:
        """What the panel shows for the pause state."""
        if self.state is PauseState.RUNNING and self.arm_paused:
            return "paused (by the job)"
        return LABELS[self.state]
