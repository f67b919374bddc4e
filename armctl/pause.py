"""The pause rule, once: when armctl may send the protocol's pause toggle.

Strategy: pure.  The toggle flips the arm between running and paused, so sending it to reach
a state is only right when the arm is known to be in the other one — and one corrupted status
byte must not decide that: the state counts as known only when the last two pause reports
agree (``job.agreed_pause``, the engine's; ``PauseState`` also remembers a toggle sent that has
not acted yet).  ``pause_toggle_needed`` is the one decision; ``armctl run``'s start
(resume an arm that reports it is paused) and ``armctl.Arm``'s ``pause``/``resume`` ask it.
"""

from __future__ import annotations

from .job import agreed_pause


class PauseState:
    """The arm's pause state as armctl knows it: what the last two pause reports agree on or,
    once armctl sent a toggle the reports do not show yet, the state that toggle heads for — in
    the ``queued`` control mode a toggle acts only after the frames before it in the FIFO, so
    an arm told to pause reports it runs for a while (the lead), and a second toggle then would
    undo the first."""

    __slots__ = ("_last_two", "_heading")

    def __init__(self) -> None:
        self._last_two: tuple = ()  # replaced whole, never mutated: a reader in another thread sees one pair
        self._heading: bool | None = None  # the state a toggle sent heads for, until reported

    def add(self, paused: bool | None) -> None:
        """One pause report (None: a report without the field)."""
        self._last_two = (*self._last_two[-1:], paused)
        if self._heading is not None and self.agreed == self._heading:
            self._heading = None  # the toggle has acted

    @property
    def agreed(self) -> bool | None:
        """The pause state when the last two reports agree on it (the job engine's rule,
        ``job.agreed_pause``); None while they disagree or fewer than two came."""
        return agreed_pause(self._last_two)

    @property
    def known(self) -> bool | None:
        return self._heading if self._heading is not None else self.agreed

    def toggle_needed(self, want_paused: bool) -> bool | None:
        """``pause_toggle_needed`` from what is known; a True answer counts the toggle as sent."""
        needed = pause_toggle_needed(want_paused, self.known)
        if needed:
            self._heading = want_paused
        return needed


def pause_toggle_needed(want_paused: bool, agreed: bool | None) -> bool | None:
    """Whether to send the pause toggle so the arm ends ``want_paused``: True only when two
    agreeing reports say it is in the other state, False when they say it already is; None
    while the state is not known (a toggle on a guess may do the opposite: read again)."""
    if agreed is None:
        return None
    return agreed != want_paused
