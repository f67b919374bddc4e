"""The jog session: keys and status in, frames and taught poses out — the whole behaviour of
``armctl jog`` without a terminal, a port or a clock.

Strategy: pure, time passed in (wall seconds; ``state.last_seen`` uses the same clock).  The
edge calls ``key(name, now, state)`` for every key, ``tick(now, state)`` whenever
``next_deadline()`` falls due or status arrives, and ``finish(now, reason, code)`` on any way
out; each returns effects — ``Send(command)`` to write, ``Record(...)`` to append — and the
session keeps what the panel shows (``view()``).

Rules:
- A jog key in continuous mode goes to the ``Deadman``.  Any other key stops continuous motion
  at once, before it acts (the terminal repeats only the last key pressed, so the jog key is
  no longer being held as far as we can know).  Ctrl-C, quit, mode changes (``m``, ``Tab``),
  space, pause and errors therefore all send the neutral value first.
- Steps, gripper changes and recording need a still arm and a fresh report: they wait in a
  short queue (at most one step; a newer step press replaces a waiting one) until continuous
  motion has stopped, no move is in flight, and every pose status kind has been read since the
  arm became still.  Only one move is ever in flight: it is done when the status shows its
  target (``Target.reached``) or when its estimated time (``MotionModel``) plus one status
  rotation has passed.  A jog key pressed while a move is in flight or a pose is being recorded
  is ignored (a held key's next repeat starts the motion).
- While the arm is paused nothing but the pause toggle is sent (H5: the arm takes nothing else
  from the FIFO head while paused, so any other frame would block the resume).  Whether it is
  paused is what status kind 4 says, except just after a toggle, when the toggle is believed.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from ..core.armstate import ROTATION_S
from ..core.motion import MotionModel
from ..core.protocol import JOYSTICK_NEUTRAL, STATUS_PERIOD_S, Command, Joystick, PauseStatus, PauseToggle
from .deadman import NEVER, Deadman, DeadmanTiming
from .keymap import JOG_ACTIONS, JOINT, LINEAR, JogAxis, KeyMap
from .moves import Refused, Reported, Target, fresh, gripper_move, reported_pose, step_move
from .settings import JogSettings

from ..errors import EXIT_INTERRUPTED, EXIT_OK
STATUS_SLACK_S = 0.015  # a status frame read this long after an instant describes the arm after it


@dataclass(frozen=True)
class Send:
    command: Command


@dataclass(frozen=True)
class Record:
    mode: str
    pose: Reported
    speed: float  # deg/s for joint mode, mm/min for linear mode


@dataclass
class _InFlight:
    label: str
    target: Target
    lands_s: float
    end_s: float  # estimated: landing + the motion model's duration
    give_up_s: float


@dataclass
class JogView:
    """Everything the panel shows besides the arm's state."""

    mode: str
    level: int  # 1-based
    levels: int
    stepping: bool
    paused: bool | None
    moving: str | None  # "J1+" while a continuous jog runs
    busy: str | None  # the move in flight or the action waiting
    message: str
    recorded: int
    record_path: str | None
    step_size: str
    speed: str
    joystick_value: int
    url: str = ""


def joystick_for(jog: JogAxis, offset: int) -> Joystick:
    value = JOYSTICK_NEUTRAL + jog.sign * offset
    if jog.is_linear:
        values = [JOYSTICK_NEUTRAL] * 3
        values[jog.index] = value
        return Joystick(jog.axis, tuple(values))
    return Joystick(jog.axis, (value,))


class JogSession:
    def __init__(self, settings: JogSettings, keymap: KeyMap, profile, mode: str = JOINT, *,
                 line_s: float = 0.05, time_scale: float = 1.0, recording: bool = False) -> None:
        self.settings, self.keymap, self.profile = settings, keymap, profile
        self.mode = mode
        self.level = settings.level - 1
        self.stepping = False
        self.recording = recording
        self.time_scale = time_scale
        self.line_s = line_s
        self.rotation_s = ROTATION_S / time_scale
        self.status_slack_s = STATUS_SLACK_S / time_scale
        self.deadman = Deadman(DeadmanTiming(
            initial_delay_s=settings.initial_delay_ms / 1000.0,
            repeat_gap_s=settings.repeat_gap_ms / 1000.0,
            line_s=line_s,
            refresh_s=settings.refresh_ms / 1000.0 or None,
        ))
        self.model = MotionModel(profile)
        self.paused: bool | None = None
        self._pause_sent_s = NEVER
        self.pending: deque = deque()  # ("step", JogAxis) | ("gripper", pwm, name) | ("record",)
        self.in_flight: _InFlight | None = None
        self._still_s = NEVER  # strict: the arm is still from here on (records, gripper)
        self._step_base_s = NEVER  # lenient: a step may start from status read since here
        self.done = False
        self.exit_code = EXIT_OK
        self.reason = ""
        self.message = ""
        self.recorded = 0
        self.unrecorded = 0
        self._jog_label = ""

    # --- the edge's calls -------------------------------------------------------------------

    def key(self, name: str, now: float, state) -> list:
        if self.done:
            return []
        self._observe(now, state)
        if name == "ctrl-c":
            return self.finish(now, "interrupted (Ctrl-C)", EXIT_INTERRUPTED)
        action = self.keymap.action(name, self.mode)
        jog = JOG_ACTIONS.get(action)
        if jog is not None and not self.stepping:
            return self._continuous(jog, now)
        out = self._stop_motion(now)
        if jog is not None:
            out += self._queue_step(jog)
        elif action is None:
            self.message = f"{name}: not bound in {self.mode} mode"
        else:
            out += getattr(self, f"_do_{action}")(now)
        return out + self._run_pending(now, state)

    def tick(self, now: float, state) -> list:
        if self.done:
            return []
        self._observe(now, state)
        out = [Send(c) for c in self.deadman.poll(now)]
        return out + self._run_pending(now, state)

    def finish(self, now: float, reason: str, exit_code: int = EXIT_OK) -> list:
        """Stop at once and end the session (quit, Ctrl-C, an error, the terminal gone)."""
        out = self._stop_motion(now)
        if not self.done:
            self.done, self.reason, self.exit_code = True, reason, exit_code
            self.unrecorded = sum(1 for item in self.pending if item[0] == "record")
            self.pending.clear()
        return out

    def next_deadline(self) -> float | None:
        """When ``tick`` has something to do without a key (None: only status can change it)."""
        return self.deadman.next_deadline()

    @property
    def waiting(self) -> bool:
        """True while something waits on status (a move in flight, a queued action)."""
        return self.in_flight is not None or bool(self.pending)

    # --- keys -------------------------------------------------------------------------------

    def _continuous(self, jog: JogAxis, now: float) -> list:
        if self.paused:
            self.message = "the arm is paused: press p to resume"
            return []
        if self.in_flight is not None or self.pending:
            self.message = f"{jog.label} ignored: waiting for {self._busy_label()}"
            return []
        self.message = ""
        self._jog_label = jog.label
        offset = self.settings.joystick_offsets[self.level]
        return [Send(c) for c in self.deadman.press(joystick_for(jog, offset), now)]

    def _stop_motion(self, now: float) -> list:
        return [Send(c) for c in self.deadman.stop(now)]

    def _queue_step(self, jog: JogAxis) -> list:
        if self.paused:
            self.message = "the arm is paused: press p to resume"
            return []
        waiting = [item for item in self.pending if item[0] == "step"]
        for item in waiting:
            self.pending.remove(item)
        self.pending.append(("step", jog))
        return []

    def _do_mode(self, now: float) -> list:
        self.mode = LINEAR if self.mode == JOINT else JOINT
        self._drop_pending("step")
        self.message = f"{self.mode} mode"
        return []

    def _do_step(self, now: float) -> list:
        self.stepping = not self.stepping
        self._drop_pending("step")
        self.message = "step jog: one increment per key press" if self.stepping else "continuous jog"
        return []

    def _do_faster(self, now: float) -> list:
        self.level = min(self.level + 1, self.settings.levels - 1)
        self.message = f"speed level {self.level + 1}"
        return []

    def _do_slower(self, now: float) -> list:
        self.level = max(self.level - 1, 0)
        self.message = f"speed level {self.level + 1}"
        return []

    def _do_open(self, now: float) -> list:
        return self._queue_gripper(self.profile.pwm.gripper_open_us, "open")

    def _do_close(self, now: float) -> list:
        return self._queue_gripper(self.profile.pwm.gripper_close_us, "close")

    def _queue_gripper(self, pwm_us: float, name: str) -> list:
        if self.paused:
            self.message = "the arm is paused: press p to resume"
            return []
        self._drop_pending("gripper")
        self.pending.append(("gripper", pwm_us, name))
        return []

    def _do_stop(self, now: float) -> list:
        self._drop_pending("step")
        self._drop_pending("gripper")
        self.message = "stopped" + (" (the move already sent finishes)" if self.in_flight else "")
        return []

    def _do_pause(self, now: float) -> list:
        self._drop_pending("step")
        self._drop_pending("gripper")
        self.paused = not self.paused
        self._pause_sent_s = now
        self.message = "pause toggle sent: " + ("pausing" if self.paused else "resuming")
        return [Send(PauseToggle())]

    def _do_record(self, now: float) -> list:
        if not self.recording:
            self.message = "nothing recorded: start with --record FILE"
            return []
        self.pending.append(("record",))
        return []

    def _do_quit(self, now: float) -> list:
        return self.finish(now, "quit", EXIT_OK)

    def _drop_pending(self, kind: str) -> None:
        for item in [item for item in self.pending if item[0] == kind]:
            self.pending.remove(item)

    # --- status -----------------------------------------------------------------------------

    def _observe(self, now: float, state) -> None:
        seen = state.last_seen.get(PauseStatus.KIND)
        if state.paused is not None and seen is not None and seen >= self._pause_sent_s + self.line_s + self.rotation_s:
            self.paused = state.paused
        flight = self.in_flight
        if flight is None:
            return
        if flight.target.reached(state, flight.lands_s):
            self._step_base_s = flight.lands_s
            self._still_s = now
        elif now >= flight.give_up_s:
            self._step_base_s, self._still_s = flight.end_s, now
        else:
            return
        self.in_flight = None

    def _settled(self, state, lenient: bool) -> bool:
        base = self._step_base_s if lenient else self._still_s
        since = max(base, self.deadman.still_after_s)
        return not self.deadman.active and self.in_flight is None and fresh(state, since + self.status_slack_s)

    def _run_pending(self, now: float, state) -> list:
        out: list = []
        while self.pending and not self.done and self.in_flight is None:
            item = self.pending[0]
            if not self._settled(state, lenient=item[0] == "step"):
                break
            self.pending.popleft()
            pose = reported_pose(state, self.profile.kinematics)
            if pose is None:
                self.message = "no complete pose from the arm yet"
                continue
            try:
                out += getattr(self, f"_run_{item[0]}")(now, pose, *item[1:])
            except Refused as refused:
                self.message = str(refused)
        return out

    def _run_step(self, now: float, pose: Reported, jog: JogAxis) -> list:
        if jog.is_linear:
            size, unit = self.settings.step_mm[self.level], "mm"
            speed = self.settings.linear_speed_mm_min[self.level]
        else:
            size, unit = self.settings.step_deg[self.level], "deg"
            speed = self.settings.joint_speed_deg_s[self.level]
        command, target = step_move(jog, size, pose, speed, self.profile)
        self.message = f"step {jog.label} {size:g} {unit}"
        return self._send_move(now, pose, command, target, f"step {jog.label} {size:g} {unit}")

    def _run_gripper(self, now: float, pose: Reported, pwm_us: float, name: str) -> list:
        command, target = gripper_move(pwm_us, pose, self.settings.joint_speed_deg_s[self.level])
        self.message = f"gripper {name}: PWM {pwm_us:g} µs"
        return self._send_move(now, pose, command, target, f"gripper {name}")

    def _run_record(self, now: float, pose: Reported) -> list:
        if self.mode == JOINT:
            speed = self.settings.joint_speed_deg_s[self.level]
        else:
            speed = self.settings.linear_speed_mm_min[self.level]
        self.recorded += 1
        self.message = f"recorded pose {self.recorded}"
        return [Record(self.mode, pose, speed)]

    def _send_move(self, now: float, pose: Reported, command, target: Target, label: str) -> list:
        start = self.model.initial_pose(joints=pose.joints_deg, pwm_us=pose.pwm_us, origin_mm=pose.origin_mm)
        duration_s = self.model.plan(command, start).duration_s / self.time_scale
        lands_s = max(now, self.deadman.line_free_s) + self.line_s
        self.deadman.line_free_s = lands_s
        end_s = lands_s + duration_s
        give_up_s = end_s + self.rotation_s + STATUS_PERIOD_S / self.time_scale
        self.in_flight = _InFlight(label, target, lands_s, end_s, give_up_s)
        return [Send(command)]

    # --- the panel --------------------------------------------------------------------------

    def _busy_label(self) -> str:
        if self.in_flight is not None:
            return self.in_flight.label
        if self.pending:
            item = self.pending[0]
            return {"step": "a step", "gripper": "the gripper", "record": "the pose to record"}[item[0]]
        return ""

    def view(self, url: str = "", record_path: str | None = None) -> JogView:
        level = self.level
        if self.mode == JOINT:
            step, speed = f"{self.settings.step_deg[level]:g} deg", f"{self.settings.joint_speed_deg_s[level]:g} deg/s"
        else:
            step, speed = f"{self.settings.step_mm[level]:g} mm", f"{self.settings.linear_speed_mm_min[level]:g} mm/min"
        moving = self._jog_label if self.deadman.active else None
        return JogView(
            mode=self.mode, level=level + 1, levels=self.settings.levels, stepping=self.stepping, paused=self.paused,
            moving=moving, busy=self._busy_label() or None, message=self.message, recorded=self.recorded,
            record_path=record_path, step_size=step, speed=speed,
            joystick_value=JOYSTICK_NEUTRAL + self.settings.joystick_offsets[level], url=url,
        )
