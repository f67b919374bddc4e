"""SD-card programs (control 30/2) as the simulated arm runs them.

Strategy: the arm's SD programs are unknown to armctl, so a program is simulated as a fixed
amount of work: it holds the arm (later frames wait in the FIFO, like a long move) for
``PROGRAM_RUN_S × speed_factor`` seconds without moving it, while the three SD status kinds
report a plausible file and a run position that advances linearly.  The numbers (all
armctl's invention, one place to change):

- file length (kind 100): ``PROGRAM_BASE_LENGTH + PROGRAM_LENGTH_STEP × n`` for program ``n``
  (0 = the taught program → 1000, 1 = Route_a → 1100, …, 15 = Route_o → 2500);
- file status (kind 102): 0 no program run yet, 1 running, 2 finished, 3 stopped by an arm reset;
- run position (kind 103): 0 → file length over the run, then stays at the file length
  (or where a reset stopped it).
Pure: the time is always an argument.
"""

from __future__ import annotations

PROGRAM_RUN_S = 4.0
PROGRAM_BASE_LENGTH = 1000.0
PROGRAM_LENGTH_STEP = 100.0
STATUS_NONE, STATUS_RUNNING, STATUS_FINISHED, STATUS_STOPPED = 0, 1, 2, 3


def program_length(number: int) -> float:
    return PROGRAM_BASE_LENGTH + PROGRAM_LENGTH_STEP * number


class SdProgram:
    """The SD program state the status frames report (none run yet by default)."""

    def __init__(self) -> None:
        self.number: int | None = None
        self.length = 0.0
        self.start_s = 0.0
        self.duration_s = 0.0
        self._stopped_at_s: float | None = None
        self._paused_at_s: float | None = None

    def start(self, number: int, now_s: float, speed_factor: float = 1.0) -> float:
        """Start program ``number``; returns how long it holds the arm."""
        self.number, self.length, self.start_s = number, program_length(number), now_s
        self.duration_s = PROGRAM_RUN_S * speed_factor
        self._stopped_at_s = self._paused_at_s = None
        return self.duration_s

    def pause(self, now_s: float) -> None:
        """A pause that freezes the arm mid-program (control frames acting on arrival)."""
        if self.status_at(now_s) == STATUS_RUNNING and self._paused_at_s is None:
            self._paused_at_s = now_s

    def resume(self, now_s: float) -> None:
        if self._paused_at_s is not None:
            self.start_s += now_s - self._paused_at_s
            self._paused_at_s = None

    def stop(self, now_s: float) -> None:
        """An arm reset (or a GoToPose acting on arrival) stops a running program where it is."""
        if self.status_at(now_s) == STATUS_RUNNING:
            self._stopped_at_s = now_s if self._paused_at_s is None else self._paused_at_s
            self._paused_at_s = None

    def status_at(self, now_s: float) -> int:
        if self.number is None:
            return STATUS_NONE
        if self._stopped_at_s is not None:
            return STATUS_STOPPED
        if self._paused_at_s is not None:
            return STATUS_RUNNING
        return STATUS_RUNNING if now_s < self.start_s + self.duration_s else STATUS_FINISHED

    def position_at(self, now_s: float) -> float:
        if self.number is None:
            return 0.0
        end_s = self.start_s + self.duration_s
        for frozen_s in (self._stopped_at_s, self._paused_at_s):
            if frozen_s is not None:
                end_s = min(end_s, frozen_s)
        elapsed_s = min(now_s, end_s) - self.start_s
        if self.duration_s <= 0:
            return self.length
        return self.length * max(0.0, min(1.0, elapsed_s / self.duration_s))


class Hold:
    """A segment that keeps the arm where it is for ``duration_s`` (an SD program running)."""

    kind = "still"
    note = None

    def __init__(self, command, pose, duration_s: float) -> None:
        self.command, self.start, self.end, self.duration_s = command, pose, pose, duration_s

    def sample(self, t_s: float):
        return self.start
