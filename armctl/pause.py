"""The pause rule, once: when armctl may send the protocol's pause toggle.

Strategy: pure.  The toggle flips the arm between running and paused, so sending it to reach
a state is only right when the arm is known to be in the other one — and one corrupted status
byte must not decide that: the state counts as known only when the last two pause reports
agree (``PauseReports``).  ``pause_toggle_needed`` is the one decision; ``armctl run``'s start
(resume an arm that reports it is paused) and ``armctl.Arm``'s ``pause``/``resume`` ask it.
"""

from __future__ import annotations


class PauseReports:
    """The last two pause states an arm reported (None: a report without the field)."""

    __slots__ = ("_last_two",)

    def __init__(self) -> None:
        self._last_two: tuple = ()  # replaced whole, never mutated: a reader in another thread sees one pair

    def add(self, paused: bool | None) -> None:
        self._last_two = (*self._last_two[-1:], paused)

    @property
    def agreed(self) -> bool | None:
        """The pause state when the last two reports agree on it; None while they disagree or
        fewer than two came."""
        pair = self._last_two
        if len(pair) == 2 and pair[0] == pair[1] and pair[0] is not None:
            return bool(pair[0])
        return None


def pause_toggle_needed(want_paused: bool, agreed: bool | None) -> bool | None:
    """Whether to send the pause toggle so the arm ends ``want_paused``: True only when two
    agreeing reports say it is in the other state, False when they say it already is; None
    while the state is not known (a toggle on a guess may do the opposite: read again)."""
    if agreed is None:
        return None
    return agreed != want_paused
