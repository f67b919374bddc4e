"""What a status view may show: each kind's value once two consecutive reports of it agree.

Strategy: pure.  ``AgreedReports.read(frame, now)`` takes every status frame as it is read (a
link's ``on_status``); ``shown(state)`` is ``state`` with each kind's values replaced by the
last ones two consecutive reports of it agreed on (armctl/core/evidence.py ``agreed``) while one
of its last two reports still reads them, None where none did (yet) or both since read another.
A status frame has no checksum (PROTOCOL.md H9): ``ArmState`` holds back a position, joints or
origin report beyond the arm's reach, but one within reach passes, and the other kinds (pause
and PWM, wrist, the SD program's three) are taken as read — so the latest report of a kind is
no proof of its value (``armctl status`` showed w0 1.58° for 0°, an SD file length of 1.97e-38
for 0 on ``sim://?noise=0.05&corrupt=0.05``).  A kind that keeps changing (an arm moving, an SD
program running) has no agreed value and is shown as not known: the reports prove no one value.
One report that differs, between two that read the agreed value, is a corrupted one or the first
of a change: the value is still shown (at most one report old), so a still arm's values do not
blink to unknown at each corrupted report (a third of the lines of ``--watch --json`` did, on seed 2).
The position and joints are the exception to "not known while changing": a moving arm's never
agree, and showing them unknown hid the one thing a user watches the arm for (``status --once``
printed null for them with a joint move under way).  With no agreed value, such a kind shows the
report before its latest, a rotation late, once the latest tells it was not a blip: each within
the arm's reach of the one before (``ArmState.jump_between``: its top speed) and the latest not
back where the one before it was (``TARGET_MM``, ``TARGET_DEG``: a reading's resolution) — a
corrupted report between two true ones of a still arm is never shown, a moving arm's are.  Two
corrupted reports of a kind in a row, the second within reach of the first, would show the first
for a rotation: the reports alone cannot tell that from motion.
"""

from __future__ import annotations

from collections import deque
from copy import deepcopy

from .armstate import MOVING_KINDS, ArmState, judged_values
from .evidence import AGREEING_REPORTS, agreed
from .job_readings import TARGET_DEG, TARGET_MM
from .protocol import STATUS_KINDS, STATUS_ROTATION, PositionStatus


class AgreedReports:
    """The last ``AGREEING_REPORTS`` frames of each kind, as read (a held-back one included)."""

    def __init__(self) -> None:
        # kind -> its last three reports (frame, read at): the last two judge agreement, all three a move
        self.reports: dict = {kind: deque(maxlen=3) for kind in STATUS_ROTATION}
        self.agreed: dict = {}  # kind -> the last frame AGREEING_REPORTS consecutive reports agreed on

    def read(self, frame, now: float = 0.0) -> None:
        """One status frame read (``Link.on_status``'s signature: from its reader thread)."""
        reports = self.reports[frame.KIND]
        reports.append((frame, now))
        if agreed(report for report, _ in reports) is not None:
            self.agreed[frame.KIND] = frame

    def value(self, kind: int, state: ArmState):
        """The frame of ``kind`` shown: the last one agreed on, while one of the last reports
        reads it; else, of a position or joints kind, the report before the latest when the
        latest shows it was no blip (module docstring; ``state`` judges the reach)."""
        frame, reports = self.agreed.get(kind), self.reports[kind]
        if frame is not None and any(report == frame for report, _ in list(reports)[-AGREEING_REPORTS:]):
            return frame
        if kind not in MOVING_KINDS or len(reports) < 3:
            return None
        (first, first_s), (middle, middle_s), (last, last_s) = reports
        jump = state.jump_between
        if jump(first, middle, middle_s - first_s) or jump(middle, last, last_s - middle_s) or _back(first, last):
            return None
        return middle

    def unknown(self, state: ArmState) -> list[str]:
        """The names of the kinds with no value shown (``value``)."""
        return [STATUS_KINDS[kind].NAME for kind in STATUS_ROTATION if self.value(kind, state) is None]

    def shown(self, state: ArmState) -> ArmState:
        """``state``'s ages and counts with only the values shown (``value``; None elsewhere)."""
        view = ArmState(last_seen=deepcopy(state.last_seen), frames=state.frames, suspect_frames=state.suspect_frames)
        for kind in STATUS_ROTATION:
            frame = self.value(kind, state)
            if frame is not None:
                view._apply(frame)
        return view


def _back(before, after) -> bool:
    """``after`` reads where ``before`` did, within a reading's resolution."""
    tolerance = TARGET_MM if after.KIND == PositionStatus.KIND else TARGET_DEG
    return all(abs(a - b) <= tolerance for a, b in zip(judged_values(before), judged_values(after)))
