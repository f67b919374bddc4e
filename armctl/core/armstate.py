"""What the arm last told us: the nine status kinds merged into one state, each with its age.

Strategy: pure.  ``ArmState.update(frame, now)`` takes a decoded status frame and the time it
was read; nothing here reads a clock or a port.  The status reader only knows bytes; this is
where H9's second half lives — a value that jumps faster than the arm can move is *suspect*
and is held back until the next frame of its kind confirms it (one corrupted frame with a
plausible frame on either side changes nothing; a real jump, e.g. after a reset, is accepted
one frame later): armctl/core/evidence.py's rule of a confirmed jump (``reach``, ``beyond_reach``).
The worktable origin, which never moves by itself, is judged so too: any change of it is held
until the next report of it agrees (a corrupted origin read before a job became its start frame
of reference: a first move planned ~3 m long, and a false "frames may have been lost").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from operator import attrgetter

from .evidence import beyond_reach, reach
from .protocol import (
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    FileLengthStatus,
    FileStatus,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PositionStatus,
    RunPositionStatus,
    StatusFrame,
    WorktableStatus,
    WristStatus,
)

# A full rotation of the nine kinds takes 9 × 30 ms; a kind unseen for three rotations is stale.
ROTATION_S = len(STATUS_ROTATION) * STATUS_PERIOD_S
STALE_AFTER_S = 3 * ROTATION_S
# Slack on top of the arm's top speed before a jump counts as suspect: the status resolution
# (0.1 mm, 0.01 deg) and the jitter of when a frame is read.
_JUMP_SLACK_MM = 2.0
_JUMP_SLACK_DEG = 2.0
# The worktable origin never moves by itself (a G54 or a reset sets it): any change beyond half
# its status step (0.1 mm) is a jump, held back until the next report of it agrees — one
# corrupted origin report must not become the job's start frame of reference.
_ORIGIN_SLACK_MM = 0.05


@dataclass
class ArmState:
    """The merged view of the arm. Values are ``None`` until their kind has been seen."""

    max_speed_mm_s: float | None = None  # None: do not judge plausibility
    max_joint_speed_deg_s: float | None = None
    x_mm: float | None = None
    y_mm: float | None = None
    z_mm: float | None = None
    joints_deg: list = field(default_factory=lambda: [None] * 6)
    worktable_mm: list = field(default_factory=lambda: [None] * 3)
    paused: bool | None = None
    pwm_us: int | None = None
    w0_deg: float | None = None
    w1_deg: float | None = None
    file_length: float | None = None
    file_status: int | None = None
    run_position: float | None = None
    last_seen: dict = field(default_factory=dict)  # kind → time it was last accepted
    frames: int = 0
    suspect_frames: int = 0
    _held: dict = field(default_factory=dict)  # kind → suspect frame awaiting confirmation

    @property
    def complete(self) -> bool:
        """True once every one of the nine kinds has been seen."""
        return len(self.last_seen) == len(STATUS_ROTATION)

    @property
    def position_mm(self) -> tuple | None:
        if self.x_mm is None:
            return None
        return (self.x_mm, self.y_mm, self.z_mm)

    def age(self, kind: int, now: float) -> float | None:
        seen = self.last_seen.get(kind)
        return None if seen is None else now - seen

    def stale_kinds(self, now: float) -> list[int]:
        ages = {k: self.age(k, now) for k in STATUS_ROTATION}
        return [k for k, age in ages.items() if age is None or age > STALE_AFTER_S]

    def update(self, frame: StatusFrame, now: float) -> bool:
        """Merge one status frame read at ``now``; False when it was held back as suspect."""
        self.frames += 1
        kind = frame.KIND
        if kind in _JUDGED_KINDS:  # only these can jump (jump_between)
            seen = self.last_seen.get(kind)
            if seen is not None:
                previous = self._current(kind)
                if previous is not None and self.jump_between(previous, frame, now - seen):
                    held = self._held.get(kind)
                    if held is None or self.jump_between(held[0], frame, now - held[1]):
                        self._held[kind] = (frame, now)
                        self.suspect_frames += 1
                        return False
        if self._held:
            self._held.pop(kind, None)
        _APPLY[kind](self, frame)
        self.last_seen[kind] = now
        return True

    def update_many(self, frames: list) -> None:
        """``update`` for each (frame, read time) of ``frames``, in order: the same state.  The
        kinds taken as read (not judged for jumps) are merged by their last frame alone — each
        sets only its own values and time, which a later frame of its kind overwrites — and the
        judged kinds kind by kind (``_merge_judged``: a kind is judged against its own frames
        alone).  ``Link`` merges the frames of its virtual runs so, when the state is read
        (``Link.state``)."""
        latest, judged = {}, {}
        for item in frames:
            kind = item[0].KIND
            if kind in _JUDGED_KINDS:
                run = judged.get(kind)
                if run is None:
                    judged[kind] = [item]
                else:
                    run.append(item)
            else:
                latest[kind] = item
        self.frames += len(frames)
        for kind, run in judged.items():
            self._merge_judged(kind, run)
        last_seen = self.last_seen
        for kind, (frame, now) in latest.items():  # never held: only the judged kinds are
            _APPLY[kind](self, frame)
            last_seen[kind] = now

    def _merge_judged(self, kind: int, run: list) -> None:
        """``update`` (less the frame count) for each (frame, read time) of ``run``, all of one
        judged kind, in order: each frame judged against the values last accepted and the frame
        held (``jump_between``'s test: armctl/core/evidence.py), only the last accepted applied."""
        speed, slack = self._limits(kind)
        held = self._held.get(kind)
        if speed is None:  # nothing is judged: the last frame is taken
            accepted, seen = run[-1]
            held = None
        else:
            values_of = _VALUE_GETTERS[kind]
            seen = self.last_seen.get(kind)
            previous = None if seen is None else self._current(kind)
            accepted, suspect = None, 0
            for frame, now in run:
                values = values_of(frame)
                if previous is not None and beyond_reach(previous, values, reach(speed, now - seen, slack)):
                    # a jump: taken only once the next report lands within reach of the held one
                    if held is None or beyond_reach(values_of(held[0]), values, reach(speed, now - held[1], slack)):
                        held = (frame, now)
                        suspect += 1
                        continue
                held, previous, seen, accepted = None, values, now, frame
            self.suspect_frames += suspect
        if held is None:
            self._held.pop(kind, None)
        else:
            self._held[kind] = held
        if accepted is not None:
            _APPLY[kind](self, accepted)
            self.last_seen[kind] = seen

    def jump_between(self, before: StatusFrame | tuple, after: StatusFrame, elapsed_s: float) -> bool:
        """``after`` is beyond the arm's reach of ``before`` (a frame or its values) ``elapsed_s``
        later: a jump, of a kind judged for jumps (evidence.py ``reach``, ``beyond_reach``)."""
        kind = after.KIND
        if kind not in _JUDGED_KINDS:
            return False
        speed, slack = self._limits(kind)
        if speed is None:
            return False
        values = _VALUE_GETTERS[kind]
        limit = reach(speed, elapsed_s, slack)
        return beyond_reach(before if type(before) is tuple else values(before), values(after), limit)

    def _limits(self, kind: int) -> tuple[float | None, float]:
        """How fast a judged kind's readings may change (None: not judged) and the slack on top
        (``reach``): the position at the arm's top speed, the joints at its joint speed, the
        worktable origin not at all (it never moves by itself)."""
        if kind == _POSITION_KIND:
            return self.max_speed_mm_s, _JUMP_SLACK_MM
        if kind == _WORKTABLE_KIND:
            return 0.0, _ORIGIN_SLACK_MM
        return self.max_joint_speed_deg_s, _JUMP_SLACK_DEG

    def _current(self, kind: int) -> tuple | None:
        """The values the state holds for a kind judged for jumps (as ``judged_values`` of its frame)."""
        if kind == PositionStatus.KIND and self.x_mm is not None:
            return (self.x_mm, self.y_mm, self.z_mm)
        if kind == JointsLowStatus.KIND and self.joints_deg[0] is not None:
            return tuple(self.joints_deg[0:3])
        if kind == JointsHighStatus.KIND and self.joints_deg[3] is not None:
            return tuple(self.joints_deg[3:6])
        if kind == _WORKTABLE_KIND and self.worktable_mm[0] is not None:
            return tuple(self.worktable_mm)
        return None

    def _apply(self, frame: StatusFrame) -> None:
        _APPLY[frame.KIND](self, frame)

    # What each kind sets (``_APPLY`` below: one lookup per frame, not a chain of isinstance).
    def _apply_position(self, frame: PositionStatus) -> None:
        self.x_mm, self.y_mm, self.z_mm = frame.x_mm, frame.y_mm, frame.z_mm

    def _apply_joints_low(self, frame: JointsLowStatus) -> None:
        self.joints_deg[0:3] = [frame.j1_deg, frame.j2_deg, frame.j3_deg]

    def _apply_joints_high(self, frame: JointsHighStatus) -> None:
        self.joints_deg[3:6] = [frame.j4_deg, frame.j5_deg, frame.j6_deg]

    def _apply_worktable(self, frame: WorktableStatus) -> None:
        self.worktable_mm = [frame.x_mm, frame.y_mm, frame.z_mm]

    def _apply_pause(self, frame: PauseStatus) -> None:
        self.paused, self.pwm_us = frame.paused, frame.pwm_us

    def _apply_wrist(self, frame: WristStatus) -> None:
        self.w0_deg, self.w1_deg = frame.w0_deg, frame.w1_deg

    def _apply_file_length(self, frame: FileLengthStatus) -> None:
        self.file_length = frame.value

    def _apply_file_status(self, frame: FileStatus) -> None:
        self.file_status = frame.raw

    def _apply_run_position(self, frame: RunPositionStatus) -> None:
        self.run_position = frame.value

    def to_json(self) -> dict:
        """The object ``armctl status --json`` prints."""
        return {
            "x": self.x_mm,
            "y": self.y_mm,
            "z": self.z_mm,
            "joints": list(self.joints_deg),
            "worktable": list(self.worktable_mm),
            "paused": self.paused,
            "pwm": self.pwm_us,
            "w0": self.w0_deg,
            "w1": self.w1_deg,
            "file_length": self.file_length,
            "file_status": self.file_status,
            "run_position": self.run_position,
        }


_APPLY = {
    PositionStatus.KIND: ArmState._apply_position,
    JointsLowStatus.KIND: ArmState._apply_joints_low,
    JointsHighStatus.KIND: ArmState._apply_joints_high,
    WorktableStatus.KIND: ArmState._apply_worktable,
    PauseStatus.KIND: ArmState._apply_pause,
    WristStatus.KIND: ArmState._apply_wrist,
    FileLengthStatus.KIND: ArmState._apply_file_length,
    FileStatus.KIND: ArmState._apply_file_status,
    RunPositionStatus.KIND: ArmState._apply_run_position,
}
# The kinds whose values are judged for jumps (``jump_between``): the others are taken as read.
MOVING_KINDS = frozenset((PositionStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND))  # change as the arm moves
_JUDGED_KINDS = MOVING_KINDS | {WorktableStatus.KIND}

_VALUE_NAMES = {
    PositionStatus: ("x_mm", "y_mm", "z_mm"),
    JointsLowStatus: ("j1_deg", "j2_deg", "j3_deg"),
    JointsHighStatus: ("j4_deg", "j5_deg", "j6_deg"),
    WorktableStatus: ("x_mm", "y_mm", "z_mm"),
}


_VALUE_GETTERS = {frame_class.KIND: attrgetter(*names) for frame_class, names in _VALUE_NAMES.items()}
_POSITION_KIND = PositionStatus.KIND
_WORKTABLE_KIND = WorktableStatus.KIND


def judged_values(frame: StatusFrame) -> tuple:
    """The three readings of a position or joints frame, in order (read directly: every frame)."""
    return _VALUE_GETTERS[frame.KIND](frame)
