"""Run one job through one pacing strategy against the simulated arm, in virtual time.

Strategy: the same job engine ``armctl run`` drives (armctl/core/job.py) — it feeds the strategy the
status frames, writes when the strategy allows, and ends the job by the same rules (at rest at
the last target, the deadline, the abort sequence) — with this module as its host: the clock
jumps from event to event (the next status byte, the next moment the strategy may write, the
engine's own next time), so an hour of arm time costs seconds.  The loop is the one host driver
(armctl/host/driver.py) with the simulated arm as its link (``_ArmLink``) and this module's hooks
(``_BenchHost``).  Every strategy row goes through
the engine; for the baselines armctl's streamer only watches (what is known done, the end of
the job), the baseline paces.  The simulator's true state (FIFO, drops, what executed when) is
read only for the result, never by the strategy (except the omniscient baseline, which exists
to be unfair).  The result carries both: ``job_s`` is the simulator's truth (when the arm
finished its last frame), ``arm_time_s`` and ``outcome`` are what the engine concluded, as
``armctl run`` prints them ("arm time: …").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, NamedTuple, Sequence

from ..core.actions import Wait, Write
from ..host.driver import Host, drive
from ..core.job import Job, RunView, agreed_pause, resume_frames
from ..host.jobflow import READ_ROTATIONS, RESUME_SETTLE_S
from ..core.motion import MotionModel
from ..core.protocol import Command, PauseStatus, PauseToggle, StatusReader, STATUS_PERIOD_S, STATUS_ROTATION
from ..sim.connector import HISTORY_FRAMES
from ..sim.model import SimulatedArm
from ..core.streamer import Streamer

EPSILON_S = 1e-9
STILL_SAMPLE_S = 0.01  # how finely motion after an abort is measured


@dataclass
class RunResult:
    frames: int
    written: int
    dropped: int
    job_s: float  # until the arm finished its last frame (or stopped for good): the simulator's truth
    peak_occupancy: int  # the FIFO's true peak
    peak_queued_s: float  # the most motion ever queued ahead of the arm when a frame landed
    moving_after_abort_s: float | None = None
    timed_out: bool = False
    aborted_at_s: float | None = None  # when the abort sequence was written
    outcome: str = "running"  # the engine's (armctl/core/job.py Outcome), as ``armctl run`` would end
    arm_time_s: float | None = None  # the engine's arm time, as ``armctl run`` prints it (finished jobs)
    resume_line: int | None = None  # the engine's resume line (1-based job frame), as the summary prints it


@dataclass(frozen=True)
class Event:
    """Something the scenario does to the arm at a time, outside the strategy's control
    (a pause pressed on the arm, …): ``command`` written to the line at ``at_s``."""

    at_s: float
    command: Command


class Frame(NamedTuple):
    """A job frame as the engine takes it: the command and where it is (its index, 1-based)."""

    command: Command
    line: int


def job_engine(commands: Sequence[Command], strategy, arm: SimulatedArm,
               abort_sequence: Sequence[Command] = (PauseToggle(),)) -> Job:
    """The engine for one run: armctl's streamer paces its own row; for a baseline a streamer
    with the host's nominal model only watches, so every row ends by the same rules."""
    streamer = getattr(strategy, "streamer", None)
    pacing = None
    if streamer is None:
        streamer = Streamer(MotionModel(arm.profile), arm.pose, baud=arm.options.baud)
        pacing = strategy
    total = len(commands)
    view = RunView(total_frames=total, estimated_job_s=0.0, lead_s=streamer.lead_s, capacity=streamer.limit_frames)
    statements = (Frame(commands[k], k + 1) for k in range(total))  # lazily: a long job stays flat in memory
    # ``done`` needs a proven FIFO size, as for ``armctl run`` (link.fifo_proven): probed, or the
    # simulated arm's own FIFO at least the host profile's
    proven = streamer.planner.model.profile.connector.fifo_proven(arm.options.fifo_frames)
    return Job(streamer, statements, view, pacing=pacing, abort_sequence=tuple(abort_sequence), fifo_proven=proven)


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
    settle: bool = False,
) -> RunResult:
    """Stream ``commands`` with ``strategy`` until the engine says the job is over (or, with
    ``abort_after_frames``, until the abort sequence is written: the motion after it is then
    measured on the arm itself).

    ``on_write(index, now)`` follows every job frame written, ``on_status(now)`` every batch of
    status frames the strategy has read (and the end of the job); ``line``, if given, gets "job", "event" or "abort" for
    each frame written, in the order they go on the wire (= the arm's arrival indexes).
    ``settle``: after the abort, run the engine to its end (as ``armctl run`` does before its
    summary and resume line) instead of measuring the motion after the abort.
    """
    line = _Discard() if line is None else line  # not kept unless asked for: memory stays flat
    job = job_engine(commands, strategy, arm, abort_sequence)
    link = _ArmLink(arm)  # a fresh arm's 0; an arm already read from (as ``armctl run`` does first) goes on
    stop_after = None if abort_after_frames is None else min(abort_after_frames, len(commands))
    host = _BenchHost(job, arm, link, sorted(events, key=lambda e: e.at_s), stop_after, time_limit_s,
                      on_write, on_status, line, settle)
    try:
        drive(job, link, host)
    except _Over:
        if host.timed_out:
            return _result(arm, len(commands), host.written, link.now_s, None, job, timed_out=True)
    aborted_at = host.aborted_at
    moving_after = _motion_after(arm, aborted_at, time_limit_s) if aborted_at is not None and not settle else None
    result = _result(arm, len(commands), host.written, link.now_s, moving_after, job)
    result.aborted_at_s = aborted_at
    return result


class _Over(Exception):
    """The bench's own end of a run: its time limit, an abort whose motion it measures, no event left."""


class _ArmLink:
    """The simulated arm as the host driver's link, in the bench's own virtual time: a wait
    jumps to the clock reading the host named (``_BenchHost.waiting``), at least ``EPSILON_S``
    on; the frames that arrived meanwhile are read at the next turn."""

    error = None

    def __init__(self, arm: SimulatedArm) -> None:
        self.arm, self.now_s = arm, arm.now_s

    def clock(self) -> float:
        return self.now_s

    def write(self, frame: bytes) -> None:
        self.arm.write(frame, self.now_s)

    def wait(self, until_s: float, news=None) -> None:
        self.now_s = max(until_s, self.now_s + EPSILON_S)


class _BenchHost(Host):
    """The bench's hooks of the host driver: before each action the arm run up to now, its
    status frames into the engine, the scenario's events and the abort; the clock's next reading
    the first of the arm's next event, the engine's time and the next scenario event."""

    def __init__(self, job: Job, arm: SimulatedArm, link: _ArmLink, events: list, stop_after: int | None,
                 time_limit_s: float, on_write, on_status, line, settle: bool) -> None:
        self.job, self.arm, self.link, self.events, self.stop_after = job, arm, link, events, stop_after
        self.time_limit_s, self.on_write, self.on_status, self.line, self.settle = (
            time_limit_s, on_write, on_status, line, settle)
        self.reader = StatusReader()
        self.written = 0
        self.aborted_at: float | None = None
        self.timed_out = False

    def now(self, clock) -> float:
        return self.link.now_s

    def turn(self) -> None:
        job, arm, now, events = self.job, self.arm, self.link.now_s, self.events
        frames = self.reader.feed(arm.advance(now))
        taken = 0
        while taken < len(frames):  # every frame into the engine (it stops at each that is news)
            news = job.receive_statuses(frames[taken:], [now] * (len(frames) - taken))
            taken = len(frames) if news is None else taken + news + 1
        if frames and self.on_status is not None:
            self.on_status(now)
        while events and events[0].at_s <= now + EPSILON_S:
            arm.write(events.pop(0).command.encode(), now)
            self.line.append("event")
        if self.stop_after is not None and self.written >= self.stop_after and self.aborted_at is None:
            self.aborted_at = now
            job.request_stop()

    def wrote(self, action: Write, now: float) -> None:
        self.job.wrote(now)
        if action.statement is None:
            self.line.append("abort")
            return
        self.line.append("job")
        if self.on_write is not None:
            self.on_write(self.written, now)
        self.written += 1

    def waiting(self, action: Wait, now: float) -> float:
        if self.aborted_at is not None and not self.settle:
            self.done(action, now)
            raise _Over
        if now > self.time_limit_s:
            self.timed_out = True
            raise _Over
        candidates = [self.arm.next_event_time(), action.until_s]
        if self.events:
            candidates.append(self.events[0].at_s)
        upcoming = min((t for t in candidates if t is not None), default=None)
        if upcoming is None:
            raise _Over
        return upcoming

    def done(self, action, now: float) -> None:
        if self.on_status is not None:
            self.on_status(now)  # the engine's last word: at rest at the last target confirms the rest


START_ROTATIONS = 1 + READ_ROTATIONS  # ``armctl run`` reads all nine kinds and two more rotations before it writes


def start_run(arm: SimulatedArm, line: list[str], control_on_arrival: bool) -> None:
    """What ``armctl run`` does on an arm before its first frame (jobflow.read_arm): read the
    status a few rotations; an arm that twice reports it is paused gets ``job.resume_frames`` for
    the control mode the host believes (on arrival a RESET CONNECTOR first, then the toggle), and
    on arrival the move the pause froze is let finish."""
    reader, reports = StatusReader(), []
    rotation_s = STATUS_PERIOD_S * len(STATUS_ROTATION)
    until = arm.now_s + START_ROTATIONS * rotation_s
    reports += [f.paused for f in reader.feed(arm.advance(until)) if isinstance(f, PauseStatus)]
    if agreed_pause(reports) is True:
        for command in resume_frames(control_on_arrival):
            arm.write(command.encode(), arm.now_s)
            line.append("resume")
        arm.advance(arm.now_s + START_ROTATIONS * rotation_s)
        deadline_s = arm.now_s + RESUME_SETTLE_S
        while control_on_arrival and not arm.idle and arm.now_s < deadline_s:
            arm.advance(arm.now_s + rotation_s)


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


def _result(arm: SimulatedArm, total: int, written: int, now: float, moving_after, job: Job,
            timed_out=False) -> RunResult:
    executor = arm.executor  # its run-long counters: the execution log is only a recent window
    return RunResult(
        frames=total, written=written, dropped=arm.frames_dropped,
        job_s=now if executor.last_end_s is None else executor.last_end_s,
        peak_occupancy=arm.peak_fifo_occupancy, peak_queued_s=executor.peak_wait_s,
        moving_after_abort_s=moving_after, timed_out=timed_out,
        outcome=str(job.view.outcome), arm_time_s=job.view.arm_time_s, resume_line=job.view.resume_line(),
    )
