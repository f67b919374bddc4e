"""How a host could pace frames to the arm: armctl's streamer and the baselines it is judged by.

Strategy: every pacing strategy answers the same three calls — ``next_write_time(now, command)``,
``wrote(command, now, tag)``, ``receive_status(frame, now)`` — so one virtual-time driver runs
them all against the same simulated arm.  The baselines show why they are not used:

* ``NaiveStrategy`` writes at the line rate: fastest to write, drops frames once moves last
  longer than a frame time;
* ``FixedDelayStrategy`` waits a fixed time between frames: too slow for short moves, drops
  for long ones;
* ``StopAndGoStrategy`` waits until the arm is seen at each target: never drops, never keeps the
  arm fed;
* ``OmniscientStrategy`` reads the simulator's true FIFO occupancy: the physical best, which no
  real host can do.
"""

from __future__ import annotations

from ..core.motion import ArmPose, MotionModel, Planner
from ..core.protocol import CONNECTOR_BUFFER_FRAMES, DEFAULT_BAUD, FRAME_SIZE, PositionStatus, frame_seconds
from ..core.streamer import Streamer

# Times this close are the same instant (the virtual-time driver writes at ``when`` if it is
# within this of ``now``); the omniscient check must not be skipped on a rounding difference.
TIME_TOLERANCE_S = 1e-9


class _LinePaced:
    """Common part: one frame at a time on the wire."""

    name = ""

    def __init__(self, baud: int = DEFAULT_BAUD) -> None:
        self.frame_s = frame_seconds(baud)
        self.wire_free_s = 0.0
        self.sent = 0

    def wrote(self, command, now: float, tag=None) -> None:
        self.wire_free_s = max(now, self.wire_free_s) + self.frame_s
        self.sent += 1

    def receive_status(self, frame, now: float) -> None:
        pass


class NaiveStrategy(_LinePaced):
    name = "naive"

    def next_write_time(self, now: float, command=None) -> float:
        return max(now, self.wire_free_s)


class FixedDelayStrategy(_LinePaced):
    name = "fixed delay"

    def __init__(self, delay_s: float, baud: int = DEFAULT_BAUD) -> None:
        super().__init__(baud)
        self.delay_s = delay_s
        self.last_write_s: float | None = None

    def wrote(self, command, now: float, tag=None) -> None:
        super().wrote(command, now, tag)
        self.last_write_s = now

    def next_write_time(self, now: float, command=None) -> float:
        earliest = self.wire_free_s if self.last_write_s is None else self.last_write_s + self.delay_s
        return max(now, earliest)


class StopAndGoStrategy(_LinePaced):
    """Writes a frame, then waits until the arm reports that frame's target (and its planned
    time has passed, for frames that do not move)."""

    name = "stop-and-go"
    TOLERANCE_MM = 0.5

    def __init__(self, model: MotionModel, start: ArmPose, baud: int = DEFAULT_BAUD) -> None:
        super().__init__(baud)
        self.planner = Planner(model, start)
        self.waiting_for = None  # (target xyz, earliest end time)
        self.reached = True

    def wrote(self, command, now: float, tag=None) -> None:
        super().wrote(command, now, tag)
        segment = self.planner.feed(command)
        self.waiting_for = (segment.end.xyz, self.wire_free_s + segment.duration_s)
        self.reached = False

    def receive_status(self, frame, now: float) -> None:
        if self.reached or not isinstance(frame, PositionStatus):
            return
        target, end_s = self.waiting_for
        close = max(abs(a - b) for a, b in zip((frame.x_mm, frame.y_mm, frame.z_mm), target)) <= self.TOLERANCE_MM
        self.reached = close and now >= end_s

    def next_write_time(self, now: float, command=None) -> float | None:
        return max(now, self.wire_free_s) if self.reached else None


class OmniscientStrategy(_LinePaced):
    """Knows the true occupancy of the connector's FIFO: writes whenever a slot will be free
    when the frame lands.  Needs the simulator itself; no real host has this."""

    name = "omniscient"

    def __init__(self, arm, capacity: int = CONNECTOR_BUFFER_FRAMES, baud: int = DEFAULT_BAUD) -> None:
        super().__init__(baud)
        self.arm = arm
        self.capacity = capacity

    def next_write_time(self, now: float, command=None) -> float | None:
        start = max(now, self.wire_free_s)
        if start > now + TIME_TOLERANCE_S:
            return start
        now = start  # the same instant, give or take rounding: the driver will write now
        # Frames still on the wire will take slots too; a slot must be free for this one.
        in_flight = -(-self.arm.host_bytes_in_flight(now) // FRAME_SIZE)
        if self.arm.fifo_occupancy + in_flight < self.capacity:
            return now
        return None


class StreamerStrategy:
    """armctl's streamer, as the benchmark drives it."""

    name = "armctl"

    def __init__(self, model: MotionModel, start: ArmPose, lead_s: float, baud: int = DEFAULT_BAUD) -> None:
        self.streamer = Streamer(model, start, lead_s=lead_s, baud=baud)

    def next_write_time(self, now: float, command=None) -> float | None:
        return self.streamer.next_write_time(now, command)

    def wrote(self, command, now: float, tag=None) -> None:
        self.streamer.wrote(command, now, tag)

    def receive_status(self, frame, now: float) -> None:
        self.streamer.receive_status(frame, now)
