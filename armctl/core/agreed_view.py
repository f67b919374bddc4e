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
"""

from __future__ import annotations

from collections import deque
from copy import deepcopy

from .armstate import ArmState
from .evidence import AGREEING_REPORTS, agreed
from .protocol import STATUS_KINDS, STATUS_ROTATION


class AgreedReports:
    """The last ``AGREEING_REPORTS`` frames of each kind, as read (a held-back one included)."""

    def __init__(self) -> None:
        self.latest: dict = {kind: deque(maxlen=AGREEING_REPORTS) for kind in STATUS_ROTATION}
        self.agreed: dict = {}  # kind -> the last frame AGREEING_REPORTS consecutive reports agreed on

    def read(self, frame, now: float = 0.0) -> None:
        """One status frame read (``Link.on_status``'s signature: from its reader thread)."""
        latest = self.latest[frame.KIND]
        latest.append(frame)
        if agreed(latest) is not None:
            self.agreed[frame.KIND] = frame

    def value(self, kind: int):
        """The frame of ``kind`` shown: the last one agreed on, while one of the last reports reads it."""
        frame = self.agreed.get(kind)
        return frame if frame is not None and frame in tuple(self.latest[kind]) else None

    def unknown(self) -> list[str]:
        """The names of the kinds with no value shown (``value``)."""
        return [STATUS_KINDS[kind].NAME for kind in STATUS_ROTATION if self.value(kind) is None]

    def shown(self, state: ArmState) -> ArmState:
        """``state``'s ages and counts with only the values shown (``value``; None elsewhere)."""
        view = ArmState(last_seen=deepcopy(state.last_seen), frames=state.frames, suspect_frames=state.suspect_frames)
        for kind in STATUS_ROTATION:
            frame = self.value(kind)
            if frame is not None:
                view._apply(frame)
        return view
