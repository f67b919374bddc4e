"""How long a job takes: the motion-time model played against the line and the lead.

Strategy: pure and streaming.  Frames are fed in order; each one is written as early as the
streamer would allow — the line is free and the motion queued ahead of the arm is within the
lead — lands one frame time later, and runs when the arm is done with the one before.  What
comes out is the job time a perfect host would reach, the time the arm spends waiting for the
line (line-bound) against the time the line waits for the arm (arm-bound), the path length and
the deepest queue.  Memory does not grow with the job.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from .motion import ArmPose, MotionModel, Planner, speed_note
from .protocol import DEFAULT_BAUD, LinearMove, RunProgram, frame_seconds
from ..script.source import MAX_JOB_MOTION_S, Diagnostic


@dataclass
class Estimate:
    frames: int = 0
    job_s: float = 0.0  # from the first byte written to the end of the last frame
    motion_s: float = 0.0  # the sum of every frame's duration
    arm_waiting_s: float = 0.0  # the arm idle, waiting for the next frame (line-bound time)
    path_mm: float = 0.0  # Cartesian path length (lines and arcs)
    joint_path_deg: float = 0.0  # lead-joint degrees of joint moves
    peak_queue_frames: int = 0
    peak_queue_s: float = 0.0
    notes: list = field(default_factory=list)  # planning notes (clamped speeds, …), first few

    @property
    def line_bound_share(self) -> float:
        """Share of the job time the arm spent waiting for the line."""
        return self.arm_waiting_s / self.job_s if self.job_s > 0 else 0.0

    def to_json(self) -> dict:
        return {
            "frames": self.frames, "job_s": round(self.job_s, 3), "motion_s": round(self.motion_s, 3),
            "line_bound_share": round(self.line_bound_share, 4), "arm_bound_share": round(1 - self.line_bound_share, 4),
            "path_mm": round(self.path_mm, 1), "joint_path_deg": round(self.joint_path_deg, 1),
            "peak_queue_frames": self.peak_queue_frames, "peak_queue_s": round(self.peak_queue_s, 3),
        }


def motion_time_overrun(statement, motion_s: float) -> Diagnostic | None:
    """E012 at ``statement`` when the job's motion time ``motion_s`` (by the profile's model, up
    to and including that statement) passes ``MAX_JOB_MOTION_S``: the one place run, estimate and
    lint judge a job too long (``G4 P3e38`` or ``U3e38`` would otherwise keep ``run`` going for ever)."""
    if motion_s <= MAX_JOB_MOTION_S:
        return None
    hours = MAX_JOB_MOTION_S / 3600
    return Diagnostic.of("E012", statement.span, f"the job's motion time passes {hours:g} hours here "
                         f"(the profile's motion model): one job may hold at most {hours:g} hours",
                         "check the delays (G4 P is in milliseconds), speeds and external-axis values; "
                         "split a longer job")


SD_PROGRAM_NOTE = "PROGRAM n: the SD program's own run time is unknown to armctl and not included"


class JobEstimator:
    """Feed commands in order with ``add``; read ``result`` at any time."""

    MAX_NOTES = 5

    def __init__(self, model: MotionModel, start: ArmPose, lead_s: float | None = None, baud: int = DEFAULT_BAUD):
        """``lead_s`` defaults to the streamer's lead."""
        # The streamer's numbers, imported here rather than with the module: lint imports this
        # module for motion_time_overrun alone, and the streamer costs every start (issue 13).
        from .streamer import DEFAULT_LEAD_S, limit_frames

        self.planner = Planner(model, start)
        self._feed_line, self._max_linear_mm_min = self.planner.feed_line, model.profile.speed.max_linear_mm_min
        self.lead_s = DEFAULT_LEAD_S if lead_s is None else lead_s
        # the streamer never lets more frames be in flight than this (see streamer.py)
        self.frame_limit = limit_frames(model.profile.connector.fifo_frames)
        self.frame_s = frame_seconds(baud)
        self.result = Estimate()
        self._wire_free = 0.0
        self._arm_free = 0.0  # when the arm finishes everything so far
        self._ends: deque[float] = deque()  # end times of frames possibly still queued

    def add(self, command) -> float:
        """Plan one more frame; returns its duration.  A LinearMove is timed without its segment
        (``Planner.feed_line``: the same seconds and length, issue 23), every other command planned."""
        if type(command) is LinearMove and command.speed_mm_min > 0:
            duration_s, length = self._feed_line(command)
            speed, limit = command.speed_mm_min, self._max_linear_mm_min
            return self._count(command, duration_s, "line", length, speed_note(speed, limit) if speed > limit else None)
        segment = self.planner.feed(command)
        return self._count(command, segment.duration_s, segment.kind, segment.length, segment.note)

    def _count(self, command, duration_s: float, kind: str, length: float, note: str | None) -> float:
        """One frame of ``duration_s`` written as early as the streamer would allow (the module docstring)."""
        result = self.result
        write = max(self._wire_free, self._arm_free - self.lead_s)
        ends = self._ends
        while ends and ends[0] <= write:
            ends.popleft()
        if len(ends) >= self.frame_limit:  # the FIFO bound: wait until the oldest queued frame ends
            write = max(write, ends[len(ends) - self.frame_limit])
        land = write + self.frame_s
        self._wire_free = land
        if result.frames and land > self._arm_free:
            result.arm_waiting_s += land - self._arm_free
        start = max(land, self._arm_free)
        self._arm_free = start + duration_s
        result.frames += 1
        result.motion_s += duration_s
        result.job_s = self._arm_free
        if kind in ("line", "arc"):
            result.path_mm += length
        elif kind == "joint":
            result.joint_path_deg += length
        if note and len(result.notes) < self.MAX_NOTES:
            result.notes.append(note)
        if isinstance(command, RunProgram) and SD_PROGRAM_NOTE not in result.notes:
            result.notes.append(SD_PROGRAM_NOTE)
        while ends and ends[0] <= land:
            ends.popleft()
        ends.append(self._arm_free)
        result.peak_queue_frames = max(result.peak_queue_frames, len(ends))
        result.peak_queue_s = max(result.peak_queue_s, self._arm_free - land)
        return duration_s


def estimate_commands(commands, model: MotionModel, start: ArmPose, lead_s: float | None = None,
                      baud: int = DEFAULT_BAUD) -> Estimate:
    estimator = JobEstimator(model, start, lead_s, baud)
    for command in commands:
        estimator.add(command)
    return estimator.result
