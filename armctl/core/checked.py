"""A checked job is a value: read once, linted once, estimated once, then streamed as checked.

Strategy: two steps, each done once, each a frozen value the next layer takes.
- ``check(snapshot, profile, initial, from_line)`` → ``CheckedScript``: what is known before any
  port opens — lint's report over the whole script (``armctl lint``'s checks) and, when it has no
  errors, whether ``from_line`` can start the job.  ``refusal()`` is the ``ScriptError`` that
  refuses it (nothing opened, nothing sent), or None.  ``armctl run``, ``estimate``, ``Arm.run``,
  the server and the bench take the value: none of them lints again.  Only what depends on the
  arm is checked again, from the arm's report: a move's one line (its missing words are the
  arm's) and the line a ``--resume`` proves (``starting_at``).
- ``prepare(checked, model, state, lead_s, baud)`` → ``CheckedJob``: the job from the arm's reported
  state (``start_from_state``: its pose, the compiler's initial state), compiled and planned
  from there by the estimate, which refuses what compiles differently from that pose (a G91
  offset from where the arm is) or runs too long (E012).  ``plan`` does the same from a pose the
  caller gives (``run --dry-run`` and ``estimate``: the profile's fixed pose 0).

The frames are not held: a statement and its planned segment take about 2.6 KB, a day's job
millions of frames, and a run's memory stays flat in the job's length.  ``statements()``
compiles the same snapshot from the same initial state and line — the compiler is
deterministic, so what streams is frame for frame what was estimated.  Neither pass pays per
frame for what repeats (issue 23): a repeat pass that ran exactly as the one before is yielded
again from its statements (armctl/script/repeats.py), and the estimate times a LinearMove
without building its segment (``Planner.feed_line``); the streamer's gate plans each frame's
segment once, as it is written.

Pure: no port, no clock, nothing printed; errors are ``ScriptError`` (nothing was sent).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ..errors import ScriptError


@dataclass(frozen=True)
class CheckedScript:
    """A script snapshot checked against one profile: lint's ``report`` (from ``initial``, the
    modal state known before line 1: None for a job, the arm's for a move) and, for a script
    without errors, the ``from_line`` check (``from_line_error``)."""

    snapshot: Any  # script.ScriptSnapshot: the bytes read once
    profile: Any  # profile.Profile
    report: Any  # lint.engine.FileReport
    initial: Any = None  # script.InitialState, or None
    from_line: int = 1
    from_line_error: ScriptError | None = None

    @property
    def name(self) -> str:
        return self.snapshot.name

    @property
    def diagnostics(self) -> list:
        return self.report.diagnostics

    @property
    def errors(self) -> int:
        """Lint's count of errors."""
        return self.report.errors

    def lint_error(self) -> ScriptError | None:
        """The lint errors as one ``ScriptError``, or None."""
        report = self.report
        if not report.errors:
            return None
        return ScriptError.of(report.diagnostics, report.errors)

    def refusal(self) -> ScriptError | None:
        """Why this script cannot run: its lint errors, else a ``from_line`` it cannot start at."""
        return self.lint_error() or self.from_line_error

    def starting_at(self, from_line: int) -> CheckedScript:
        """The same check for another first line (a resume): only the line's check is redone."""
        if from_line == self.from_line:
            return self
        return replace(self, from_line=from_line, from_line_error=from_line_errors(self.snapshot, from_line))

    def frames(self) -> int | None:
        """How many frames the job sends from ``from_line`` (None when it does not compile): its
        statements, one frame each, compiled again (some 6 µs a line; the frames not held) — what
        ``prepare``'s estimate counts from the arm's report, which sets values, never which lines
        run.  For a summary of a job stopped before it was planned (``armctl run --json``)."""
        compilation = self.snapshot.compile(initial=self.initial, from_line=self.from_line)
        count = sum(1 for _ in compilation)
        return None if compilation.error_count else count

    def checks(self, profile, initial, from_line: int) -> bool:
        """This is the check ``check(self.snapshot, profile, initial, from_line)`` would make."""
        return self.profile is profile and self.initial == initial and self.from_line == from_line


def check(snapshot, profile, initial=None, from_line: int = 1) -> CheckedScript:
    """Lint ``snapshot`` (a ``ScriptSnapshot``) against ``profile`` from ``initial``; when it has
    no errors, check that ``from_line`` can start the job."""
    from ..lint.engine import lint_lines

    report = lint_lines(snapshot.lines(), snapshot.name, profile, initial=initial)
    line_error = from_line_errors(snapshot, from_line) if not report.errors else None
    return CheckedScript(snapshot, profile, report, initial, from_line, line_error)


def checked_for(source, profile, initial=None, from_line: int = 1) -> CheckedScript:
    """``source`` (a snapshot, or a ``CheckedScript``) checked against ``profile`` from ``initial``
    and ``from_line``: a ``CheckedScript`` that is this very check is taken as it is."""
    if isinstance(source, CheckedScript):
        if source.checks(profile, initial, from_line):
            return source
        source = source.snapshot
    return check(source, profile, initial, from_line)


def from_line_errors(snapshot, from_line: int) -> ScriptError | None:
    """A resume line the compiler cannot start at (inside an arc, inside a repeat block, past
    the end) is an error like any other; None when ``from_line`` can start the job."""
    if from_line <= 1:
        return None
    compilation = snapshot.compile(from_line=from_line)
    compilation.finish()
    if not compilation.error_count:
        return None
    return ScriptError.of(compilation.diagnostics, compilation.error_count)


@dataclass(frozen=True)
class CheckedJob:
    """A checked script on one arm: where it starts (``start``, a ``motion.Pose``; ``initial``,
    the compiler's ``InitialState``), its ``estimate`` from there, and the lead and baud rate
    it was estimated for.  ``statements()``: the frames to send, as estimated."""

    script: CheckedScript
    start: Any
    initial: Any
    estimate: Any  # estimate.Estimate
    lead_s: float
    baud: int

    @property
    def snapshot(self):
        return self.script.snapshot

    @property
    def from_line(self) -> int:
        return self.script.from_line

    @property
    def total_lines(self) -> int:
        return self.script.report.lines

    def statements(self):
        """The compilation the estimate made, made again (deterministic: frame for frame)."""
        return self.snapshot.compile(initial=self.initial, from_line=self.from_line)


def plan(checked: CheckedScript, model, start, initial, lead_s: float, baud: int) -> CheckedJob:
    """``checked`` (without errors) estimated from ``start`` and ``initial``; ``ScriptError`` for
    a job whose motion time passes ``MAX_JOB_MOTION_S`` (E012 at the line where it does) or
    that does not compile from this initial state."""
    from .estimate import JobEstimator, motion_time_overrun

    from ..script.source import MAX_JOB_MOTION_S

    estimator = JobEstimator(model, start, lead_s, baud)
    add, result = estimator.add, estimator.result
    compilation = checked.snapshot.compile(initial=initial, from_line=checked.from_line)
    for statement in compilation:
        add(statement.command)
        if result.motion_s > MAX_JOB_MOTION_S:  # motion_time_overrun's own first test, without the call
            raise ScriptError([motion_time_overrun(statement, result.motion_s)], errors=1)
    # the arm's reported state can make a line fail that passed the check (a G91 offset from the
    # real pose): then it is refused here, and nothing goes
    if compilation.error_count:
        raise ScriptError.of(compilation.diagnostics, compilation.error_count)
    return CheckedJob(checked, start, initial, estimator.result, lead_s, baud)


def prepare(checked: CheckedScript, model, state, lead_s: float, baud: int) -> CheckedJob:
    """``checked`` planned from the arm's reported ``state`` (``ScriptError`` when it cannot run
    from there)."""
    return plan(checked, model, *start_from_state(model, state), lead_s, baud)


def start_from_state(model, state):
    """The streamer's start pose and the compiler's initial state, from the arm's report: its
    X/Y/Z and its joints as reported (``MotionModel.reported_pose``: an unverified profile's
    kinematics never decide where the arm starts)."""
    from ..script import InitialState

    joints = tuple(state.joints_deg)
    pose = model.reported_pose(state.position_mm, joints, float(state.pwm_us), tuple(state.worktable_mm))
    initial = InitialState(pose=tuple(pose.cartesian), joints_deg=joints, pwm_us={1: float(state.pwm_us)})
    return pose, initial


def start_at(model, joints: tuple | None = None, pwm_us: float | None = None, origin_mm: tuple = (0.0, 0.0, 0.0)):
    """The start pose and initial state of an arm at ``joints`` with ``pwm_us`` (default: the
    profile's fixed pose 0 and initial pulse, as ``armctl run --dry-run`` assumes)."""
    from ..script import InitialState

    pose = model.initial_pose(joints=joints, pwm_us=pwm_us, origin_mm=origin_mm)
    joints = tuple(model.profile.poses[0]) if joints is None else joints
    pwm_us = pose.pwm_us[0] if pwm_us is None else pwm_us
    initial = InitialState(pose=tuple(pose.cartesian), joints_deg=joints, pwm_us={1: pwm_us})
    return pose, initial
