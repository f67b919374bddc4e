"""Lint's own rules: one small function per code, over compiled statements and the arm tracker.

Strategy: the compiler (armctl/script) already rejects everything that cannot become a frame
— syntax, unknown words, protocol ranges, unpaired arcs, missing modal values (speed, pose,
PWM, G91 offsets from an unknown position), undefined parameters, bad repeat counts: those are
its E0xx codes and lint reports them as they are.  The rules here judge what *does* compile
against the arm's profile and common sense: geometry (L1xx), speeds and units (L2xx), PWM
(L3xx), parameters, loops and empty scripts (L4xx, fed by armctl/lint/scan.py) and the state
the script leaves the arm in (L5xx).

A statement rule is ``check(statement, arm) -> iterable of (where, message, hint[, rests_on])``
(a generator, or — for the rules every Cartesian line meets — a function returning ``()`` when
it finds nothing, which costs no generator per line: issue 13),
where is a ``SourceSpan`` or a ``WordAt`` (a word's span, computed only if the finding is kept)
and ``rests_on`` names the profile numbers the finding depends on ("section.key" or a whole
"section"): the engine reports a finding on an error code as a warning when any of them is an
illustrative number of the packaged default (armctl/host/profile.py's provenance) — a finding is
only as true as the numbers it rests on.  A finding without ``rests_on`` rests on geometry or
on the protocol alone.  It runs before ``arm`` (armctl/lint/tracker.py) advances past the
statement, so ``arm`` describes the arm as the statement finds it.  An END rule is ``check(arm)``.  Rules read the profile through
``arm.profile`` and never see each other; the engine adds the code, severity and location
filters.  Thresholds that are judgement calls are named constants below.
"""

from __future__ import annotations

import math
import re
from typing import Iterable, Iterator, NamedTuple, Optional

from ..core.kinematics import Unreachable, box_problem, has_solution, inverse
from ..core.motion import arc_through, circle_through
from ..core.protocol import AccelLinearMove, ArcEnd, ArcStart, JointMove, LinearMove, as_f32
from ..script import SourceSpan
from ..core.speed_limits import CARTESIAN_MOVES, speed_limit  # L201's limit, which the feed override clamps to
from .registry import END, check
from .tracker import cartesian_target, pwm_channel_of

ARC_POINT_TOLERANCE_MM = 0.05  # arc points closer than this to each other or to one line: degenerate
ARC_RADIUS_TOLERANCE = (0.5, 0.01)  # R may differ from the circle by max(0.5 mm, 1 %) (as motion.py notes)
# A target this many times the profile's reach away is an error whatever the profile's provenance
# (the packaged reach is illustrative, so L103 is otherwise a warning there): no plausible arm
IMPLAUSIBLE_REACH_FACTOR = 2.0
ARC_SAMPLES = 24  # points checked along an arc against the workspace box and reach radius
UNIT_SLIP_FACTOR = 5.0  # a G6 F above 5× the joint maximum reads as mm/min
SLOW_CARTESIAN_MM_MIN = 60.0  # a Cartesian F below 1 mm/s reads as deg/s
PWM_TOLERANCE_US = 0.5  # "equal" PWM values, for the gripper's end state

TOOL_DOWN_DEG = (180.0, 0.0, 0.0)  # the attitude tried to tell "attitude" from "distance" (A180 B0 C0)
Finding = tuple  # (where: SourceSpan | WordAt, message, hint[, rests_on: tuple of profile keys])


class WordAt(NamedTuple):
    """Where word ``letter`` is on the statement's line (else its head) — found only when a
    finding is kept, because finding a word's columns means parsing the line again."""

    statement: object
    letter: str

    @property
    def line(self) -> int:
        return self.statement.span.line

    @property
    def text(self) -> str:
        return self.statement.span.text

    def resolve(self) -> SourceSpan:
        return self.statement.word_span(self.letter) or self.statement.span


_at = WordAt


def _mm(value: float) -> str:
    return f"{value:.1f}".rstrip("0").rstrip(".") if abs(value - round(value)) > 1e-9 else f"{round(value)}"


def _xyz(point) -> str:
    return f"({_mm(point[0])}, {_mm(point[1])}, {_mm(point[2])})"


# --- L1xx geometry --------------------------------------------------------------------------------


@check("L101", on=[ArcEnd])
def arc_degenerate(statement, arm) -> Iterator[Finding]:
    start, points = _arc_points(statement, arm)
    if start is None:
        return
    p0, p1, p2 = points
    line = start.line
    if math.dist(p0, p2) <= ARC_POINT_TOLERANCE_MM:
        yield (statement.span, f"the arc ends where it starts {_xyz(p0)}: three points cannot define a full circle",
               "split the circle into two arcs, each with its own G300/G301 pair")
    elif math.dist(p0, p1) <= ARC_POINT_TOLERANCE_MM or math.dist(p1, p2) <= ARC_POINT_TOLERANCE_MM:
        which = "start" if math.dist(p0, p1) <= ARC_POINT_TOLERANCE_MM else "end"
        yield (statement.span, f"the G300 point on line {line} coincides with the arc's {which} point {_xyz(p1)}",
               "the G300 point must lie on the arc between its start and its end")
    elif circle_through(p0, p1, p2, ARC_POINT_TOLERANCE_MM) is None:
        yield (statement.span, f"the arc's start {_xyz(p0)}, G300 point {_xyz(p1)} and end {_xyz(p2)} lie on one line",
               "for a straight line use G1; for an arc move the G300 point off the line")


@check("L102", on=[ArcEnd])
def arc_radius(statement, arm) -> Iterator[Finding]:
    start, points = _arc_points(statement, arm)
    if start is None:
        return
    circle = circle_through(*points, ARC_POINT_TOLERANCE_MM)
    if circle is None:
        return  # L101
    radius, written = circle[1], start.command.radius_mm
    absolute, relative = ARC_RADIUS_TOLERANCE
    if abs(written - radius) > max(absolute, relative * radius):
        yield (_at(start, "R"), f"R{written:g} disagrees with the circle through the start, the G300 point and the G301"
               f" point on line {statement.line} (radius {radius:.2f} mm)", f"write R{radius:.2f}")


def _arc_points(statement, arm):
    """(the G300 Statement, (start, via, end) points) of the arc this G301 ends, or (None, None)."""
    start = arm.arc_start
    if start is None or arm.arc_from is None:
        return None, None
    return start, (arm.arc_from[:3], cartesian_target(start.command)[:3], cartesian_target(statement.command)[:3])


_AXIS = re.compile(r"robot ([XYZ]) = ")
_WORKSPACE = ("workspace",)  # the box and the reach radius
_KINEMATICS = ("links", "joints")  # inverse kinematics: link lengths and joint limits


@check("L103", on=CARTESIAN_MOVES + (JointMove,))
def outside_workspace(statement, arm) -> Iterable[Finding]:
    command = statement.command
    kind = type(command)
    if kind is JointMove:
        return _joint_target_outside(statement, arm)
    pose = cartesian_target(command)
    if kind is not ArcStart and pose == arm.pose:
        return ()  # the arm is already there (a gripper- or speed-only line): one mistake, one finding
    problem = None if arm.surely_reachable(pose) else arm.reach_problem(pose, lambda: _reach_problem(pose, arm))
    if problem is not None:
        message, hint, rests_on = problem
        axis = _AXIS.match(message)
        span = _at(statement, axis.group(1)) if axis else statement.span
        what = "the G300 point" if kind is ArcStart else "target"
        return [(span, f"{what} {_xyz(pose)}: {message}", hint, rests_on)]
    if kind is ArcEnd:
        return _arc_outside(statement, arm)
    return ()


def _reach_problem(pose, arm) -> Optional[tuple[str, str, tuple[str, ...]]]:
    """(message, hint, rests_on) for a worktable pose the arm cannot take, or None: first the
    workspace box and reach radius, then a joint solution inside the limits — and if there is
    none, whether the attitude or the distance is at fault (the same point tool down).  Asked
    only when ``arm.surely_reachable`` cannot say (issue 13), through the tracker's cache."""
    robot = arm.robot_xyz(pose)
    profile = arm.profile
    implausible = _beyond_any_desktop_arm(robot, profile.workspace.reach_mm)
    if implausible is not None:
        return implausible
    problem = box_problem(robot, profile.workspace)
    if problem is not None:
        return problem, _workspace_hint(arm, problem), _WORKSPACE
    near = arm.ik_hint()
    if near is None:
        near = profile.poses[0]
    target = (*robot, pose[3], pose[4], pose[5])
    if has_solution(target, profile.links, near, profile.joint_limits_deg):
        return None  # the common case, decided without choosing the best solution
    try:
        inverse(target, profile.links, near, profile.joint_limits_deg)
        return None  # pragma: no cover - has_solution says when inverse succeeds
    except Unreachable as error:
        problem = str(error)
    try:
        inverse((*robot, *TOOL_DOWN_DEG), profile.links, near, profile.joint_limits_deg)
    except Unreachable:
        return (problem, "neither this attitude nor tool down (A180 B0 C0) has a joint solution: the point is out"
                " of the arm's reach; bring it nearer the arm", _KINEMATICS)
    attitude = " ".join(f"{letter}{_mm(value)}" for letter, value in zip("ABC", pose[3:6]))
    return (problem, f"the point is within reach, but not with the attitude {attitude}: the wrist cannot turn"
            " that far; change the attitude (A180 B0 C0 = tool down reaches it)", _KINEMATICS)


def _beyond_any_desktop_arm(robot, reach_mm: float) -> Optional[tuple[str, str, tuple[str, ...]]]:
    """A point farther from the robot origin than ``IMPLAUSIBLE_REACH_FACTOR`` × the profile's
    reach: (message, hint, no numbers to rest on) — an error even while the reach is only
    illustrative, since no desktop arm's real reach is that far off its profile (``G1 X2000``
    must never run: a typo'd digit, metres for millimetres).  Else None."""
    distance = math.sqrt(sum(v * v for v in robot))
    limit = IMPLAUSIBLE_REACH_FACTOR * reach_mm
    if distance <= limit:
        return None
    axis = max(range(3), key=lambda k: abs(robot[k]))
    return (f"robot {'XYZ'[axis]} = {robot[axis]:.1f} mm puts the tool {distance:.0f} mm from the robot origin, more than"
            f" {IMPLAUSIBLE_REACH_FACTOR:g}x the profile's reach ({reach_mm:g} mm): beyond any desktop arm",
            "a digit too many, or metres for millimetres? targets are in mm", ())


def _joint_target_outside(statement, arm) -> Iterator[Finding]:
    joints = statement.command.joints_deg
    if any(not low <= j <= high for j, (low, high) in zip(joints, arm.profile.joint_limits_deg, strict=True)):
        return  # L104 says it
    robot = arm.profile.kinematics.forward(joints)[:3]
    problem = box_problem(robot, arm.profile.workspace)
    if problem is not None:
        yield (statement.span, f"G6 puts the tool at robot {_xyz(robot)}: {problem}", _workspace_hint(arm, problem),
               (*_WORKSPACE, "links"))


def _arc_outside(statement, arm) -> Iterator[Finding]:
    start, points = _arc_points(statement, arm)
    if start is None:
        return
    arc = arc_through(*points, ARC_POINT_TOLERANCE_MM)
    if arc is None:
        return  # L101
    for k in range(1, ARC_SAMPLES):
        point = _arc_point(arc, points[0], arc.sweep_rad * k / ARC_SAMPLES)
        implausible = _beyond_any_desktop_arm(arm.robot_xyz(point), arm.profile.workspace.reach_mm)
        if implausible is not None:
            message, hint, rests_on = implausible
            yield (statement.span, f"the arc from line {start.line} passes {_xyz(point)}: {message}", hint, rests_on)
            return
        problem = box_problem(arm.robot_xyz(point), arm.profile.workspace)
        if problem is not None:
            yield (statement.span, f"the arc from line {start.line} passes {_xyz(point)}: {problem}",
                   "the arc bulges beyond its three points; move the G300 point or split the arc", _WORKSPACE)
            return


def _arc_point(arc, start, angle: float):
    """The point ``angle`` radians along ``arc`` from ``start`` (rotation about the arc's normal)."""
    c, n = arc.center, arc.normal
    u = tuple(start[i] - c[i] for i in range(3))
    v = (n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0])
    cos, sin = math.cos(angle), math.sin(angle)
    return tuple(c[i] + u[i] * cos + v[i] * sin for i in range(3))


def _workspace_hint(arm, problem: str) -> str:
    box, origin = arm.profile.workspace, arm.origin_mm
    if problem.startswith("robot "):
        if any(origin):
            shifted = ", ".join(f"{name} {low - o:g}…{high - o:g}" for name, (low, high), o in
                                zip("XYZ", (box.x_mm, box.y_mm, box.z_mm), origin, strict=True))
            return f"with the G54 origin at robot {_xyz(origin)} the worktable limits are {shifted} mm"
        return f"the profile's workspace is X {box.x_mm[0]:g}…{box.x_mm[1]:g}, Y {box.y_mm[0]:g}…{box.y_mm[1]:g}, " \
               f"Z {box.z_mm[0]:g}…{box.z_mm[1]:g} mm"
    return f"keep the tool point within {box.reach_mm:g} mm of the robot origin"


@check("L104", on=[JointMove])
def joint_limit(statement, arm) -> Iterator[Finding]:
    limits = arm.profile.joint_limits_deg
    for k, (angle, (low, high)) in enumerate(zip(statement.command.joints_deg, limits, strict=True), 1):
        if not low <= angle <= high:
            yield (_at(statement, f"J{k}"), f"J{k}={angle:g} is outside its limits {low:g}…{high:g} deg",
                   f"the profile allows J{k} from {low:g} to {high:g} deg", (f"joints.j{k}_deg",))


# --- L2xx speeds ----------------------------------------------------------------------------------


def _sent(statement, letter: str) -> float | None:
    """The word's value as the frame carries it (32-bit, H1), so a finding judges what is sent:
    ``S2500.00001`` goes out as 2500 and is inside 500…2500.  None when the word is absent."""
    value = statement.words.get(letter)
    if value is None:
        return None
    sent = as_f32(value)
    return value if sent is None else sent  # beyond float32: the compiler's E005 says so


def _is_unit_slip(statement, arm) -> bool:
    return (_sent(statement, "F") or 0.0) > UNIT_SLIP_FACTOR * arm.profile.speed.max_joint_deg_s


@check("L201", on=CARTESIAN_MOVES + (JointMove,))
def speed_above_max(statement, arm) -> Iterable[Finding]:
    words = statement.words
    if "F" not in words and "Q" not in words:
        return ()  # most lines: the speed is modal
    return _speed_above_max(statement, arm)


def _speed_above_max(statement, arm) -> Iterator[Finding]:
    limit = speed_limit(type(statement.command), arm.profile.speed)
    if type(statement.command) is JointMove:
        value = _sent(statement, "F")
        if value is not None and value > limit and not _is_unit_slip(statement, arm):
            yield (_at(statement, "F"), f"F{value:g} deg/s is above the profile's joint maximum {limit:g} deg/s",
                   f"write F{limit:g} or less", ("speed.max_joint_deg_s",))
        return
    for letter in ("F", "Q"):
        value = _sent(statement, letter)
        if value is not None and value > limit:
            yield (_at(statement, letter), f"{letter}{value:g} mm/min is above the profile's maximum {limit:g} mm/min",
                   f"write {letter}{limit:g} or less", ("speed.max_linear_mm_min",))


@check("L202", on=[JointMove])
def joint_speed_unit(statement, arm) -> Iterator[Finding]:
    if _is_unit_slip(statement, arm):
        value, limit = _sent(statement, "F"), arm.profile.speed.max_joint_deg_s
        yield (_at(statement, "F"), f"G6 F{value:g} means {value:g} deg/s, {value / limit:.0f}× the joint maximum"
               f" {limit:g} deg/s: it reads like mm/min", f"G6 speeds are deg/s: write e.g. F{min(30.0, limit):g}",
               ("speed.max_joint_deg_s",))


@check("L203", on=CARTESIAN_MOVES)
def cartesian_speed_unit(statement, arm) -> Iterable[Finding]:
    if "F" not in statement.words:
        return ()
    value = _sent(statement, "F")
    if value is not None and 0 < value < SLOW_CARTESIAN_MM_MIN:
        return [(_at(statement, "F"), f"F{value:g} means {value:g} mm/min ({value / 60:.2g} mm/s): it reads like deg/s",
                 f"Cartesian speeds are mm/min: {value:g} mm/s is F{value * 60:g}")]
    return ()


@check("L204", on=[AccelLinearMove])
def accel_above_max(statement, arm) -> Iterator[Finding]:
    value, limit = _sent(statement, "K"), arm.profile.speed.max_accel_mm_s2
    if value is not None and abs(value) > limit:
        yield (_at(statement, "K"), f"K{value:g} mm/s² is above the profile's maximum acceleration {limit:g} mm/s²",
               f"write K{math.copysign(limit, value):g} or a smaller magnitude", ("speed.max_accel_mm_s2",))


# --- L3xx PWM -------------------------------------------------------------------------------------


@check("L301", on=[LinearMove, JointMove, ArcStart, ArcEnd])
def pwm_channel_unwired(statement, arm) -> Iterable[Finding]:
    channel = pwm_channel_of(statement.command)
    if channel in arm.profile.pwm.channels:
        return ()
    return _pwm_channel_unwired(statement, arm, channel)


def _pwm_channel_unwired(statement, arm, channel) -> Iterator[Finding]:
    wired = arm.profile.pwm.channels
    key = ("L301", channel)
    if "T" not in statement.words and key in arm.notes:
        return  # reported once per channel unless a T word selects it again
    arm.notes.add(key)
    letter = "T" if "T" in statement.words else "S"
    yield (_at(statement, letter), f"PWM channel {channel} is not wired in the profile (wired: {', '.join(map(str, wired))})",
           "T1 selects the gripper's channel" if 1 in wired else "set pwm.channels in the profile", ("pwm.channels",))


@check("L302", on=[LinearMove, JointMove, ArcStart, ArcEnd])
def pwm_outside_range(statement, arm) -> Iterable[Finding]:
    if "S" not in statement.words:
        return ()
    value = _sent(statement, "S")
    low, high = arm.profile.pwm.range_us
    if value is not None and not low <= value <= high:
        pwm = arm.profile.pwm
        return [(_at(statement, "S"), f"S{value:g} µs is outside the profile's PWM range {low:g}…{high:g} µs",
                 f"gripper open is S{pwm.gripper_open_us:g}, closed S{pwm.gripper_close_us:g}", ("pwm.range_us",))]
    return ()


# --- L4xx parameters, loops, empty scripts: found by armctl/lint/scan.py and the engine ---------


# --- L5xx how the script leaves the arm (only when the profile's [lint] table asks) ---------------


@check("L501", on=END)
def end_gripper(arm) -> Iterator[Finding]:
    expected = arm.profile.lint.end_gripper
    statement = arm.pwm_statement.get(1)
    if expected is None or statement is None:
        return
    pwm = arm.profile.pwm
    value = arm.pwm_us[1]
    want = pwm.gripper_open_us if expected == "open" else pwm.gripper_close_us
    if abs(value - want) <= PWM_TOLERANCE_US:
        return
    other = "closed" if expected == "open" else "open"
    other_value = pwm.gripper_close_us if expected == "open" else pwm.gripper_open_us
    state = other if abs(value - other_value) <= PWM_TOLERANCE_US else f"at S{value:g}, neither open nor closed"
    key = "gripper_open_us" if expected == "open" else "gripper_close_us"
    yield (_at(statement, "S"), f"the script ends with the gripper {state} (PWM 1 last set here);"
           f" the profile expects it {expected}", f"end with a move carrying S{want:g} (pwm.{key})",
           (f"pwm.{key}", "pwm.gripper_open_us" if expected == "closed" else "pwm.gripper_close_us"))


@check("L502", on=END)
def end_paused(arm) -> Iterator[Finding]:
    expected = arm.profile.lint.end_paused
    if expected is None or arm.paused == expected:
        return
    if arm.paused:
        toggles = f"{arm.pause_count} PAUSE toggle{'' if arm.pause_count == 1 else 's'}"
        yield (arm.last_pause.span, f"the script ends paused: {toggles}, an odd number",
               "add a PAUSE to resume before the end, or remove this one")
    elif arm.last_statement is not None:
        yield (arm.last_statement.span, "the script ends running, but the profile expects it to end paused",
               "end with PAUSE")
