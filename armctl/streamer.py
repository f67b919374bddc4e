"""The pacing core: when may the next frame be written to an arm that never acknowledges?

Strategy: pure — status frames, writes and ``now`` come in as arguments; decisions come out.
The connector holds at most 200 frames and silently drops the rest, and the arm says only
where it is.  So for every frame written the streamer keeps its planned ``Segment`` (the shared
motion-time model), the moment its last byte left the wire, and two views of the arm:

* a **lower bound of frames consumed**, advanced only on evidence: a reported position (or
  joint half) lies on the path of segment k, and on no earlier segment still pending, so every
  frame before k has finished and left the FIFO.  An observation moves the bound only when
  the one before it agrees (one corrupted status frame can never move it), and a second,
  *time* bound confirms frames that leave no trace in the position (delays, M codes, control
  frames, PWM-only moves): a frame has certainly finished once even an arm ``slowest_factor``
  times slower than the model would have finished it — counting only time the arm was seen
  running, so a pause (or silence about the pause state) stops that clock;
* an **estimate** of when each frame ends, from the model, re-anchored on every observation to
  the segment the arm is most plausibly on.

A frame may be written only while (a) frames written − lower bound < capacity − margin and
(b) estimated motion queued ahead of the arm ≤ ``lead_s``, and only once the previous frame has
left the wire (writes are paced to the line, so no OS buffer hides seconds of frames).  Lost or
corrupted status frames can only hold the bound back, i.e. make the streamer more careful.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from .motion import ArmPose, MotionModel, Planner, Segment, distance_to_path
from .protocol import (
    CONNECTOR_BUFFER_FRAMES,
    DEFAULT_BAUD,
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    Command,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PositionStatus,
    StatusFrame,
    frame_seconds,
)

DEFAULT_LEAD_S = 2.0
# Frames kept free in the FIFO below its capacity: one for a frame the arm may still count while
# executing it, the rest for what no model foresees.
CAPACITY_MARGIN_FRAMES = 4
# The time bound assumes the arm is never more than this many times slower than the model.
SLOWEST_ARM_FACTOR = 2.0
# Latest a frame may reach the connector after its last byte left the host (USB adapters,
# kernel buffers), and slack per frame for the controller's own handling.
ARRIVAL_SLACK_S = 0.05
FRAME_SLACK_S = 0.02
# How close a reported value must be to a path to count as evidence (the status resolution is
# 0.1 mm and 0.01 deg; the rest covers the moment between sampling and reading).
POSITION_TOLERANCE_MM = 0.5
JOINT_TOLERANCE_DEG = 0.2
ROTATION_S = len(STATUS_ROTATION) * STATUS_PERIOD_S


@dataclass
class SentFrame:
    """A frame on its way to, in, or through the connector's FIFO."""

    index: int
    command: Command
    segment: Segment
    tag: object  # the caller's reference, e.g. the script line
    wire_end_s: float  # its last byte left the host
    est_end_s: float = 0.0  # the estimate: when the arm finishes it
    certain_end_s: float = 0.0  # the time bound: it has surely finished by then (arm-running time)


@dataclass(frozen=True)
class Observation:
    """Where the arm was seen: a segment index and how far along it (0…1)."""

    index: int
    fraction: float
    at_s: float


class Streamer:
    """Decides when the next frame may be written; see the module docstring."""

    def __init__(
        self,
        model: MotionModel,
        start: ArmPose,
        *,
        lead_s: float = DEFAULT_LEAD_S,
        capacity: int = CONNECTOR_BUFFER_FRAMES,
        margin: int = CAPACITY_MARGIN_FRAMES,
        baud: int = DEFAULT_BAUD,
        slowest_factor: float = SLOWEST_ARM_FACTOR,
        now: float = 0.0,
    ) -> None:
        if lead_s <= 0:
            raise ValueError("lead_s must be greater than 0")
        self.planner = Planner(model, start)
        self.lead_s = lead_s
        self.limit_frames = capacity - margin
        self.frame_s = frame_seconds(baud)
        self.slowest_factor = slowest_factor
        self.pending: deque[SentFrame] = deque()  # frames not yet known consumed, oldest first
        self.sent = 0
        self.consumed_lower_bound = 0
        self.wire_free_s = now
        self._last_candidate: dict[str, int | None] = {}
        self._last_done_tag = None
        # Arm-running clock for the time bound: seconds the arm was certainly not paused.
        self._running_seen_s: float | None = None
        self._paused = False
        self._pause_began_s = now
        self.status_frames = 0

    # --- writing ----------------------------------------------------------------------------

    @property
    def frames_in_flight_bound(self) -> int:
        """Frames written and not known consumed: an upper bound of the FIFO's occupancy."""
        return self.sent - self.consumed_lower_bound

    def queued_seconds(self, now: float) -> float:
        """Estimated motion queued ahead of the arm: when it will finish everything, from now."""
        if not self.pending:
            return 0.0
        return max(0.0, self.pending[-1].est_end_s - now)

    def next_write_time(self, now: float) -> float | None:
        """The earliest time ≥ now the next frame may be written if no news arrives; None while
        only new evidence can allow it (the FIFO bound is reached)."""
        if self.frames_in_flight_bound + 1 > self.limit_frames:
            return None
        lead_ok_at = self.pending[-1].est_end_s - self.lead_s if self.pending else now
        return max(now, self.wire_free_s, lead_ok_at)

    def may_write(self, now: float) -> bool:
        when = self.next_write_time(now)
        return when is not None and when <= now

    def wrote(self, command: Command, now: float, tag: object = None) -> SentFrame:
        """Record that the next frame's first byte went on the wire at ``now``."""
        segment = self.planner.feed(command)
        start_s = max(now, self.wire_free_s)
        wire_end = start_s + self.frame_s
        self.wire_free_s = wire_end
        previous = self.pending[-1] if self.pending else None
        est_start = max(wire_end, previous.est_end_s if previous else wire_end)
        certain_start = max(wire_end + ARRIVAL_SLACK_S, previous.certain_end_s if previous else 0.0)
        frame = SentFrame(
            index=self.sent, command=command, segment=segment, tag=tag, wire_end_s=wire_end,
            est_end_s=est_start + segment.duration_s,
            certain_end_s=certain_start + segment.duration_s * self.slowest_factor + FRAME_SLACK_S,
        )
        self.pending.append(frame)
        self.sent += 1
        return frame

    # --- reading ----------------------------------------------------------------------------

    def receive_status(self, frame: StatusFrame, now: float) -> None:
        """Take one status frame read at ``now``."""
        self.status_frames += 1
        if isinstance(frame, PauseStatus):
            self._note_pause_state(frame.paused, now)
        elif isinstance(frame, PositionStatus):
            self._observe((frame.x_mm, frame.y_mm, frame.z_mm), now)
        elif isinstance(frame, JointsLowStatus):
            self._observe_joint_half(0, (frame.j1_deg, frame.j2_deg, frame.j3_deg), now)
        elif isinstance(frame, JointsHighStatus):
            self._observe_joint_half(3, (frame.j4_deg, frame.j5_deg, frame.j6_deg), now)
        self._advance_by_time()

    def _note_pause_state(self, paused: bool, now: float) -> None:
        if paused and not self._paused and self._running_seen_s is not None:
            self._pause_began_s = self._running_seen_s  # it may have begun right after
        if not paused:
            if self._paused:
                # Everything still pending waited at least from the last sighting of a running
                # arm to now: push the certain end times back by that much.
                shift = now - self._pause_began_s
                for sent in self.pending:
                    sent.certain_end_s += shift
            self._running_seen_s = now
        self._paused = paused

    def _advance_by_time(self) -> None:
        if self._running_seen_s is None or self._paused:
            return
        certain_now = self._running_seen_s
        while self.pending and self.pending[0].certain_end_s <= certain_now:
            self._consume_one()

    def _consume_one(self) -> None:
        self._last_done_tag = self.pending.popleft().tag
        self.consumed_lower_bound += 1

    def _observe(self, xyz, now: float) -> None:
        candidates = []
        for sent in self.pending:
            distance, fraction = distance_to_path(sent.segment, xyz)
            if distance <= POSITION_TOLERANCE_MM:
                candidates.append((sent.index, fraction))
        self._use("position", candidates, now)

    def _observe_joint_half(self, offset: int, values, now: float) -> None:
        """Joint halves say nothing about a Cartesian segment (that would need IK), so a match
        on a joint segment counts only up to the first pending Cartesian segment."""
        candidates = []
        for sent in self.pending:
            if sent.segment.kind in ("line", "arc"):
                if candidates:
                    break
                return  # the arm may be on this Cartesian segment: no evidence from joints
            fraction = _joint_half_fraction(sent.segment, offset, values)
            if fraction is not None:
                candidates.append((sent.index, fraction))
        self._use(f"joints{offset}", candidates, now)

    def _use(self, stream: str, candidates: list[tuple[int, float]], now: float) -> None:
        """Move the lower bound and the estimate on one observation's candidate segments.

        The earliest candidate is where the arm is at least; the bound moves there only when
        the previous observation of the same stream agrees, so one corrupted frame cannot.
        """
        earliest = candidates[0][0] if candidates else None
        previous = self._last_candidate.get(stream)
        self._last_candidate[stream] = earliest
        if earliest is None:
            return
        if previous is not None:
            agreed = min(previous, earliest)
            while self.pending and self.pending[0].index < agreed:
                self._consume_one()
        self._reanchor(candidates, now)

    def _reanchor(self, candidates: list[tuple[int, float]], now: float) -> None:
        """Re-time the pending frames from the candidate the estimate finds most plausible.

        Only a segment that moves says anything about time: the arm standing on a point shared
        by a still frame tells nothing about whether that frame has run.  Seen at the very end
        of a segment, the arm finished it at or before ``now`` (the estimate may only move
        earlier); seen part-way, it finishes the rest from ``now``.
        """
        first = self.pending[0].index if self.pending else 0
        moving = [c for c in candidates if c[0] >= first and self.pending[c[0] - first].segment.length > 0]
        if not moving:
            return
        index, fraction = min(moving, key=lambda c: _distance_in_time(self.pending[c[0] - first], c[1], now))
        k = index - first
        sent = self.pending[k]
        segment = sent.segment
        if fraction >= 1.0:
            sent.est_end_s = min(sent.est_end_s, now)
        else:
            sent.est_end_s = now + (segment.duration_s - segment.time_at_fraction(fraction))
        for j in range(k + 1, len(self.pending)):
            nxt = self.pending[j]
            nxt.est_end_s = max(nxt.wire_end_s, self.pending[j - 1].est_end_s) + nxt.segment.duration_s

    # --- the end of a job ---------------------------------------------------------------------

    def estimated_finish_s(self) -> float | None:
        return self.pending[-1].est_end_s if self.pending else None

    @property
    def all_consumed(self) -> bool:
        """Every frame written is known to have finished."""
        return not self.pending

    def last_known_done(self):
        """The tag of the last frame known finished, or None."""
        return self._last_done_tag


def _distance_in_time(sent: SentFrame, fraction: float, now: float) -> float:
    """How far the estimate is from saying the arm is at ``fraction`` of ``sent`` right now."""
    segment = sent.segment
    expected_at = sent.est_end_s - segment.duration_s + segment.time_at_fraction(fraction)
    return abs(expected_at - now)


def _joint_half_fraction(segment: Segment, offset: int, values) -> float | None:
    """The fraction along a joint or still segment at which joints offset…offset+2 equal
    ``values`` within tolerance; None if never (or if the segment is Cartesian)."""
    if segment.kind not in ("joint", "still"):
        return None
    q0 = segment.start.joints[offset : offset + 3]
    q1 = segment.end.joints[offset : offset + 3]
    dq = [b - a for a, b in zip(q0, q1)]
    span = sum(d * d for d in dq)
    if span <= 1e-12:
        u = 0.0
    else:
        u = sum((v - a) * d for v, a, d in zip(values, q0, dq)) / span
        u = min(max(u, 0.0), 1.0)
    if max(abs(v - (a + d * u)) for v, a, d in zip(values, q0, dq)) > JOINT_TOLERANCE_DEG:
        return None
    return u
