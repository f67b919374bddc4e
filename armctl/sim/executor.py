"""The arm's executor: takes frames from the connector's FIFO and carries them out.

Strategy: at most one segment runs at a time; its timing and path come from the shared
motion-time model (``armctl.core.motion.MotionModel``, with the simulator's ``speed_factor``), so the
simulator, ``estimate`` and the streamer agree by construction.  The executor is a small state
machine driven by three calls from the model's event loop — ``land`` (a frame arrived),
``run_until`` (time passed) and ``pose_at`` (a status frame samples the real path) — and it
exposes the one time at which it next changes by itself (``next_event_s``: the running
segment's end).  Control frames and M codes take no time of their own (the motion model gives
an M code only its command overhead).  Pure: no clock, no I/O.

Decisions (each in one place, here):
- **H5** (``control_on_arrival=False``: ``SimOptions.control_frames="queued"``, the document's reading):
  control frames wait in the FIFO and act when they reach its head, between commands.  While
  paused the arm consumes only a PauseToggle at the head (the resume); anything else at the
  head waits — so a resume queued behind other frames never arrives (a host must send nothing
  but the resume while the arm is paused).  With ``control_on_arrival=True`` control frames
  never enter the FIFO and act the moment they land: pause freezes the running segment (an SD
  program too) mid-path and resume continues it where it stopped; GoToPose and RunProgram interrupt the
  running segment and start at once; GoToPose, RunProgram and Joystick landing while paused
  are ignored (outcome "ignored").
- Arm reset (control 12/3): stops the arm where it is (a running segment is cut short,
  outcome "interrupted"), discards the frames still waiting that landed *before* the reset
  (in H5 mode there are none: it acts at the head), clears pause, stops the joystick and a
  running SD program.  Pose, PWM, worktable origin and structure mode are kept.
- Connector reset (control 12/6): discards every frame still waiting in the FIFO (frames
  that landed after it in H5 mode, everything waiting in arrival mode); the running segment
  finishes.  The connector's byte framing is not reset.
- Arc: an ArcStart (G300) at the head waits until the next frame has landed; if that is an
  ArcEnd (G301) both are taken and run as one arc segment (both hold their slots until the
  arc ends and are logged with its start and end); otherwise the ArcStart is skipped
  (outcome "skipped") and the next frame runs as it is.
- Joystick (control 30/7): jogs only while the arm is idle; taking any other frame from the
  FIFO stops it (all axes neutral), as do pause and arm reset.  A joystick frame that lands
  while a segment runs (arrival mode only) is ignored (outcome "ignored").
- A frame framed correctly but carrying no valid command takes its slot and is skipped.
- **Reach** (issue 24; the document names no fault report, so this is an assumption, kept
  here): a motion frame whose target the arm cannot take — a Cartesian target with no joints
  inside its own limits by its own kinematics (the simulated arm's links, ``link_scale``
  included), or joint targets outside those limits — is refused as a controller refuses an
  IK failure: it takes its slot, the arm does not move (outcome "refused"), and the status
  frames keep showing where it stands, so a job holding one can never be proven finished.
  Only the target is judged: a path that leaves the reach between two reachable targets runs.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.motion import MotionModel
from ..core.protocol import (
    CONTROL_COMMANDS,
    ArcEnd,
    ArcStart,
    GoToPose,
    Joystick,
    PauseToggle,
    ResetArm,
    ResetConnector,
    RunProgram,
    SetWorktableOrigin,
    StructureMode,
)
from .connector import Connector, ReceivedFrame, RecentList
from .joystick import JoystickMotion
from .program import Hold, SdProgram

DONE, INTERRUPTED, SKIPPED, IGNORED, REFUSED, RUNNING = "done", "interrupted", "skipped", "ignored", "refused", "running"


@dataclass(eq=False)
class Execution:
    """One frame the arm took (or acted on): when it started and ended, and how."""

    index: int  # the frame's arrival index
    command: object  # the protocol command, or None for a frame carrying none
    start_s: float
    end_s: float | None = None  # None while running
    outcome: str = RUNNING
    note: str | None = None

    @property
    def duration_s(self) -> float | None:
        return None if self.end_s is None else self.end_s - self.start_s


@dataclass(eq=False)
class _Running:
    segment: object  # motion.Segment or program.Hold
    frames: list  # ReceivedFrame(s) holding slots until the segment ends
    entries: list  # their Execution records
    origin_s: float  # segment time 0 on the model's clock
    frozen_at_s: float | None = None  # segment time where a pause froze it (arrival mode)
    cartesian_at: object = None  # the segment's cartesian_at (None for a segment without one)

    def __post_init__(self) -> None:
        self.cartesian_at = getattr(self.segment, "cartesian_at", None)  # looked up once, read every status frame

    def local_s(self, now_s: float) -> float:
        return self.frozen_at_s if self.frozen_at_s is not None else now_s - self.origin_s


class Executor:
    def __init__(self, profile, connector: Connector, speed_factor: float = 1.0,
                 control_on_arrival: bool = False, start_s: float = 0.0) -> None:
        self.profile = profile
        self.connector = connector
        self.speed_factor = speed_factor
        self.control_on_arrival = control_on_arrival
        self.reports_robot_xyz = False  # status kind 0 in robot coordinates (SimOptions.status_xyz_frame)
        self.motion = MotionModel(profile, speed_factor)
        self.pose = self.motion.initial_pose()  # where the arm rests (valid while idle)
        self.origin_mm = tuple(self.pose.origin_mm)
        self.paused = False
        self.structure_mode = 0
        self.program = SdProgram()
        self.joystick = JoystickMotion(profile, speed_factor)
        self.joystick.stop(self.pose.joints, start_s)
        self.log: RecentList = RecentList()  # the most recent executions (Execution), in order
        # For the whole run, however long (the log is a window): what the benchmark reads.
        self.finished_count = 0  # executions that have ended (done, interrupted, skipped, ignored)
        self.last_end_s: float | None = None  # when the last of them ended
        self.peak_wait_s = 0.0  # the longest time from a frame landing to its execution's end
        self.now_s = start_s
        self._running: _Running | None = None

    # --- what the model's event loop calls --------------------------------------------------------

    @property
    def busy(self) -> bool:
        return self._running is not None

    def next_event_s(self) -> float | None:
        running = self._running
        if running is None or running.frozen_at_s is not None:
            return None
        return running.origin_s + running.segment.duration_s

    def run_until(self, now_s: float) -> None:
        """Finish every segment that ends by ``now_s``, starting the next ones as they free up."""
        while True:
            end_s = self.next_event_s()
            if end_s is None or end_s > now_s:
                break
            self._finish_running(end_s)
            self._start_next(end_s)
        self.now_s = max(self.now_s, now_s)

    def land(self, frame: ReceivedFrame, now_s: float) -> None:
        """A well-framed frame has fully arrived at ``now_s``."""
        self.run_until(now_s)
        if self.control_on_arrival and isinstance(frame.command, CONTROL_COMMANDS):
            self.connector.record_unbuffered(frame)
            self._act_on_arrival(frame, now_s)
        elif self.connector.land(frame):
            self._start_next(now_s)

    def pose_at(self, now_s: float):
        """The arm's true pose (``motion.ArmPose``) at ``now_s``, on the real path."""
        running = self._running
        if running is not None:
            return running.segment.sample(running.local_s(now_s))
        if self.joystick.active:
            return self.pose.replace(joints=self.joystick.joints_at(now_s))
        return self.pose

    def cartesian_at(self, now_s: float):
        """(``pose_at(now_s).cartesian`` as a plain tuple, the segment's ``end`` pose) while a
        line or an arc runs and the arm is between its ends; else None (ask ``pose_at``).  The
        status encoder's way to the same floats without the pose objects (``Segment.cartesian_at``)."""
        running = self._running
        if running is None or running.cartesian_at is None:
            return None
        values = running.cartesian_at(running.local_s(now_s))
        return None if values is None else (values, running.segment.end)

    def snapshot(self, now_s: float) -> "LiveSnapshot":
        """What a status frame built at ``now_s`` reports (computed only as far as it is read)."""
        return LiveSnapshot(self, now_s)

    # --- taking frames from the FIFO ----------------------------------------------------------

    def _start_next(self, now_s: float) -> None:
        connector = self.connector
        while self._running is None:
            head = connector.head()
            if head is None:
                return
            command = head.command
            if self.paused:
                if not isinstance(command, PauseToggle):
                    return
                self._instant(connector.take(), now_s)
                self.paused = False
                continue
            if isinstance(command, ArcStart):
                following = connector.peek(1)
                if following is None:
                    return  # the G301 has not landed yet
                if isinstance(following.command, ArcEnd):
                    self._stop_jog(now_s)
                    frames = [connector.take(), connector.take()]
                    segment = self.motion.plan(following.command, self._start_pose(), arc_start=command)
                    problem = self._beyond_reach(segment)
                    if problem is not None:
                        for taken in frames:
                            self._instant(taken, now_s, REFUSED, problem)
                        continue
                    self._run(segment, frames, now_s)
                    return
                self._instant(connector.take(), now_s, SKIPPED, "arc start not followed by its arc end")
                continue
            frame = connector.take()
            if not isinstance(command, Joystick):
                self._stop_jog(now_s)
            if command is None:
                self._instant(frame, now_s, SKIPPED, frame.error)
            elif isinstance(command, CONTROL_COMMANDS):
                self._control(frame, now_s)
            else:
                segment = self.motion.plan(command, self._start_pose())
                problem = self._beyond_reach(segment)
                if problem is not None:
                    self._instant(frame, now_s, REFUSED, problem)
                    continue
                self._run(segment, [frame], now_s)

    def _beyond_reach(self, segment) -> str | None:
        """Why the arm cannot take ``segment``'s target (module docstring, "Reach"), or None."""
        end = segment.end
        if segment.kind == "joint":
            for number, (angle, (low, high)) in enumerate(zip(end.joints, self.profile.joint_limits_deg), 1):
                if not low <= angle <= high:
                    return f"J{number} = {angle:g} deg is outside the arm's limits {low:g}…{high:g}"
            return None
        if segment.kind in ("line", "arc") and not end.kinematics.can_take(end.robot_cartesian, end.ik_hint):
            x, y, z = end.robot_cartesian[:3]
            return f"X{x:.1f} Y{y:.1f} Z{z:.1f} (robot frame) is out of the arm's reach"
        return None

    def _start_pose(self):
        if tuple(self.pose.origin_mm) != self.origin_mm:
            self.pose = self.pose.replace(origin_mm=self.origin_mm)
        return self.pose

    def _run(self, segment, frames: list, now_s: float) -> None:
        entries = [Execution(f.index, f.command, now_s, note=segment.note) for f in frames]
        self.log.extend(entries)
        self._running = _Running(segment, frames, entries, now_s)

    def _finish_running(self, end_s: float, outcome: str = DONE) -> None:
        running, self._running = self._running, None
        pose = running.segment.end if outcome == DONE else running.segment.sample(running.local_s(end_s))
        self.pose = pose
        if outcome != DONE and isinstance(running.segment, Hold):
            self.program.stop(end_s)
        for frame, entry in zip(running.frames, running.entries):
            entry.end_s, entry.outcome = end_s, outcome
            self._ended(frame, end_s)
            self.connector.finish(frame)
        self._start_pose()

    def _instant(self, frame: ReceivedFrame, now_s: float, outcome: str = DONE, note: str | None = None) -> None:
        self.log.append(Execution(frame.index, frame.command, now_s, now_s, outcome, note))
        self._ended(frame, now_s)
        self.connector.finish(frame)

    def _ended(self, frame: ReceivedFrame, end_s: float) -> None:
        self.finished_count += 1
        self.last_end_s = end_s if self.last_end_s is None else max(self.last_end_s, end_s)
        self.peak_wait_s = max(self.peak_wait_s, end_s - frame.arrival_s)

    # --- control frames -----------------------------------------------------------------------

    def _control(self, frame: ReceivedFrame, now_s: float) -> None:
        """A control frame taken from the FIFO head (H5) — the arm is idle."""
        command = frame.command
        if isinstance(command, GoToPose):
            self._run(self.motion.plan(command, self._start_pose()), [frame], now_s)
        elif isinstance(command, RunProgram):
            self._start_program(frame, now_s)
        else:
            self._instant_control(frame, now_s)

    def _act_on_arrival(self, frame: ReceivedFrame, now_s: float) -> None:
        """The H5 alternative: a control frame acts the moment it lands."""
        command, running = frame.command, self._running
        if isinstance(command, PauseToggle):
            self._instant(frame, now_s)
            self._toggle_pause(now_s)
        elif isinstance(command, (GoToPose, RunProgram, Joystick)) and self.paused:
            self._instant(frame, now_s, IGNORED, "the arm is paused")
        elif isinstance(command, (GoToPose, RunProgram)):
            if running is not None:
                self._finish_running(now_s, INTERRUPTED)
            self._control(frame, now_s)
        elif isinstance(command, Joystick) and running is not None:
            self._instant(frame, now_s, IGNORED, "joystick while a segment runs")
        else:
            self._instant_control(frame, now_s)
        self._start_next(now_s)

    def _instant_control(self, frame: ReceivedFrame, now_s: float) -> None:
        command = frame.command
        self._instant(frame, now_s)
        if isinstance(command, PauseToggle):
            self._toggle_pause(now_s)
        elif isinstance(command, ResetArm):
            self._reset_arm(frame, now_s)
        elif isinstance(command, ResetConnector):
            self.connector.clear_waiting()
        elif isinstance(command, SetWorktableOrigin):
            self.origin_mm = (command.x_mm, command.y_mm, command.z_mm)
            if self._running is None:
                self._start_pose()
        elif isinstance(command, StructureMode):
            self.structure_mode = command.mode
        elif isinstance(command, Joystick):
            self._settle_jog(now_s)
            self.joystick.set_axis(command.axis, command.values, self.pose.joints, now_s)

    def _toggle_pause(self, now_s: float) -> None:
        running = self._running
        if not self.paused:
            self.paused = True
            self._stop_jog(now_s)
            if running is not None and self.control_on_arrival:
                running.frozen_at_s = running.local_s(now_s)
                self.program.pause(now_s)
        else:
            self.paused = False
            if running is not None and running.frozen_at_s is not None:
                running.origin_s = now_s - running.frozen_at_s
                running.frozen_at_s = None
                self.program.resume(now_s)

    def _reset_arm(self, frame: ReceivedFrame, now_s: float) -> None:
        if self._running is not None:
            self._finish_running(now_s, INTERRUPTED)
        self.connector.clear_waiting(before_index=frame.index)
        self.paused = False
        self._stop_jog(now_s)
        self.program.stop(now_s)

    def _start_program(self, frame: ReceivedFrame, now_s: float) -> None:
        duration_s = self.program.start(frame.command.program, now_s, self.speed_factor)
        self._run(Hold(frame.command, self._start_pose(), duration_s), [frame], now_s)

    # --- joystick -----------------------------------------------------------------------------

    def _settle_jog(self, now_s: float) -> None:
        """Make ``pose`` the jog's current pose, so rates can change from here."""
        if self.joystick.active:
            self.pose = self.pose.replace(joints=self.joystick.joints_at(now_s))

    def _stop_jog(self, now_s: float) -> None:
        if self.joystick.active:
            self._settle_jog(now_s)
            self.joystick.stop(self.pose.joints, now_s)


class LiveSnapshot:
    """The executor's state at one instant, with the ``status.ArmSnapshot`` attributes; the
    pose is sampled on the real path and its joints (IK) or position (FK) computed only if read."""

    def __init__(self, executor: Executor, now_s: float) -> None:
        self._executor, self._now_s = executor, now_s
        self._pose = None
        self._robot_xyz = executor.reports_robot_xyz
        self.origin_mm = executor.origin_mm
        self.paused = executor.paused
        program = executor.program
        self.program_length = program.length
        self.program_status = program.status_at(now_s)
        self.program_position = program.position_at(now_s)

    @property
    def pose(self):
        if self._pose is None:
            self._pose = self._executor.pose_at(self._now_s)
        return self._pose

    @property
    def position_mm(self) -> tuple[float, float, float]:
        """Tool X, Y, Z in the worktable frame in force now (robot frame for an arm that reports it)."""
        x, y, z = self.pose.robot_cartesian[:3]
        if self._robot_xyz:
            return (x, y, z)
        ox, oy, oz = self.origin_mm
        return (x - ox, y - oy, z - oz)

    @property
    def joints_deg(self) -> tuple[float, ...]:
        return self.pose.joints

    @property
    def pwm_us(self) -> float:
        return self.pose.pwm_us[0]  # channel 1, the tool
