"""Run one job through one pacing strategy against the simulated arm, in virtual time.

Strategy: the same loop a real host runs — read status bytes, feed them to the strategy, write
the next frame when the strategy allows — but the clock jumps from event to event (the next
status byte, the next moment the strategy may write), so an hour of arm time costs seconds.
The simulator's true state (FIFO, drops, what executed when) is read only for the result,
never by the strategy (except the omniscient baseline, which exists to be unfair).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from ..protocol import Command, PauseToggle, StatusReader
from ..sim.connector import HISTORY_FRAMES
from ..sim.model import SimulatedArm

EPSILON_S = 1e-9
STILL_SAMPLE_S = 0.01  # how finely motion after an abort is measured


@dataclass
class RunResult:
    frames: int
    written: int
    dropped: int
    job_s: float  # until the arm finished its last frame (or stopped for good)
    peak_occupancy: int  # the FIFO's true peak
    peak_queued_s: float  # the most motion ever queued ahead of the arm when a frame landed
    moving_after_abort_s: float | None = None
    timed_out: bool = False
    aborted_at_s: float | None = None  # when the abort sequence was written


@dataclass(frozen=True)
class Event:
    """Something the scenario does to the arm at a time, outside the strategy's control
    (a pause pressed on the arm, …): ``command`` written to the line at ``at_s``."""

    at_s: float
    command: Command


def run_job(
    commands: Sequence[Command],
    strategy,
    arm: SimulatedArm,
    *,
    abort_after_frames: int | None = None,
    abort_sequence: Sequence[Command] = (PauseToggle(),),
    events: Sequence[Event] = (),
    time_limit_s: float = 36_000.0,
    on_write: Callable[[int, float], None] | None = None,
    on_status: Callable[[float], None] | None = None,
    line: list[str] | None = None,
) -> RunResult:
    """Stream ``commands`` with ``strategy`` until the arm is done (or aborted and still).

    ``on_write(index, now)`` follows every job frame written, ``on_status(now)`` every batch of
    status frames the strategy has read; ``line``, if given, gets "job", "event" or "abort" for
    each frame written, in the order they go on the wire (= the arm's arrival indexes).
    """
    line = _Discard() if line is None else line  # not kept unless asked for: memory stays flat
    reader = StatusReader()
    pending_events = sorted(events, key=lambda e: e.at_s)
    now = 0.0
    written = 0
    aborted_at: float | None = None
    total = len(commands)
    stop_after = total if abort_after_frames is None else min(abort_after_frames, total)
    while True:
        frames = reader.feed(arm.advance(now))
        for frame in frames:
            strategy.receive_status(frame, now)
        if frames and on_status is not None:
            on_status(now)
        while pending_events and pending_events[0].at_s <= now + EPSILON_S:
            arm.write(pending_events.pop(0).command.encode(), now)
            line.append("event")
        when = None
        if written < stop_after:
            when = strategy.next_write_time(now, commands[written])
            if when is not None and when <= now + EPSILON_S:
                arm.write(commands[written].encode(), now)
                line.append("job")
                strategy.wrote(commands[written], now, written)
                if on_write is not None:
                    on_write(written, now)
                written += 1
                continue
        elif aborted_at is None and abort_after_frames is not None:
            aborted_at = now
            for command in abort_sequence:
                arm.write(command.encode(), now)
                line.append("abort")
            break
        elif arm.idle and not pending_events:
            break
        if now > time_limit_s:
            return _result(arm, total, written, now, None, timed_out=True)
        candidates = [arm.next_event_time(), when]
        if pending_events:
            candidates.append(pending_events[0].at_s)
        upcoming = min((t for t in candidates if t is not None), default=None)
        if upcoming is None:
            break
        now = max(upcoming, now + EPSILON_S)
    moving_after = _motion_after(arm, aborted_at, time_limit_s) if aborted_at is not None else None
    result = _result(arm, total, written, now, moving_after)
    result.aborted_at_s = aborted_at
    return result


class _Discard:
    def append(self, item) -> None:
        pass


def job_frames_finished(arm: SimulatedArm, line: Sequence[str], now: float) -> int:
    """The truth a streamer's lower bound is checked against: job frames the arm has finished
    by ``now`` (``line`` as filled in by ``run_job``).  Needs the arm's whole history, so it is
    for runs of up to ``HISTORY_FRAMES`` frames (the tests')."""
    if not arm.history_complete:
        raise ValueError(f"the run is longer than the simulator's history ({HISTORY_FRAMES} frames)")
    return sum(
        1 for e in arm.execution_log
        if e.end_s is not None and e.end_s <= now + EPSILON_S and e.index < len(line) and line[e.index] == "job"
    )


def _motion_after(arm: SimulatedArm, aborted_at: float, time_limit_s: float) -> float:
    """Seconds from the abort until the arm's true position last changed."""
    now = aborted_at
    last = arm.snapshot()
    last_change = aborted_at
    still_for = 0.0
    while now < time_limit_s and still_for < 5.0:
        now += STILL_SAMPLE_S
        arm.advance(now)
        current = arm.snapshot()
        if current.position_mm != last.position_mm or current.joints_deg != last.joints_deg:
            last_change, still_for = now, 0.0
        else:
            still_for += STILL_SAMPLE_S
            if arm.idle or (arm.paused and not arm.busy):
                break
        last = current
    return last_change - aborted_at


def _result(arm: SimulatedArm, total: int, written: int, now: float, moving_after, timed_out=False) -> RunResult:
    executor = arm.executor  # its run-long counters: the execution log is only a recent window
    return RunResult(
        frames=total, written=written, dropped=arm.frames_dropped,
        job_s=now if executor.last_end_s is None else executor.last_end_s,
        peak_occupancy=arm.peak_fifo_occupancy, peak_queued_s=executor.peak_wait_s,
        moving_after_abort_s=moving_after, timed_out=timed_out,
    )
