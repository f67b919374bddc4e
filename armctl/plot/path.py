"""The path a job takes, as points to draw: the pure half of ``armctl plot``.

Strategy: walk the compiled job the way ``estimate`` does — one ``Planner`` over the
statements, from the profile's fixed pose 0 — and sample each planned ``Segment`` at evenly
spaced fractions of its path with ``Segment.sample(Segment.time_at_fraction(f))``.  So the
picture is the motion model's own geometry (straight lines, arcs on the circle through their
three points, joint moves as forward kinematics of linearly interpolated joints), never a
second one.  A G300 draws nothing by itself: its arc is drawn with the G301 that ends it and
carries both lines.  Lint findings are then pinned to the segment of their line, or — for a
line that moves nothing (a comment, a line with errors under ``--force``, the end of the
file) — to where the arm is when the job reaches that line.

Points are in the robot frame (mm), the frame of the profile's workspace box; they equal the
script's X/Y/Z unless a G54 moves the worktable origin.  No plotting library, no I/O: the
renderers (html.py, static.py) only draw what this module returns.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Iterable, NamedTuple, Optional, Sequence

from ..core.motion import ArmPose, MotionModel, Planner, Segment, arc_through
from ..core.protocol import AccelLinearMove, ArcEnd, ArcStart, GoToPose, JointMove, LinearMove

Point = tuple[float, float, float]

# Statement kinds, in drawing and legend order.
LINEAR, ACCEL, ARC, JOINT, STILL = "linear", "accel", "arc", "joint", "still"
KINDS = (LINEAR, ACCEL, ARC, JOINT, STILL)
KIND_LABELS = {
    LINEAR: "linear (G1)",
    ACCEL: "accelerated linear (G220/G222/G230)",
    ARC: "arc (G300 + G301)",
    JOINT: "joint (G6, POSE n), approximate",
    STILL: "still (delays, M codes, control)",
}
_KIND_OF = {LinearMove: LINEAR, AccelLinearMove: ACCEL, ArcEnd: ARC, JointMove: JOINT, GoToPose: JOINT}

# Why joint moves are drawn as approximate: their Cartesian curve is forward kinematics with
# the profile's link lengths, and no profile's links are measured on the arm (the packaged
# ones are illustrative, see default_profile.toml).
APPROXIMATE_NOTE = "kinematics not verified against your arm"

# Sampling density.  A straight line is exact with its two ends; an arc gets a point every
# ARC_STEP_DEG of its sweep (chord error under 0.1 % of the radius); a joint move a point every
# JOINT_STEP_DEG of its lead joint, and at least JOINT_MIN_STEPS chords, because its curve is
# only known through FK.
ARC_STEP_DEG = 5.0
JOINT_STEP_DEG = 2.0
JOINT_MIN_STEPS = 8
_SLACK = 0.01  # of a step: a 90.00005° arc (frames carry 32-bit floats) still makes 18 chords, not 19
MAX_TEXT_CHARS = 80  # of a source line in a label
VIEW_MARGIN_SHARE, VIEW_MARGIN_MIN_MM = 0.08, 10.0  # around the job in view_limits
DEFAULT_MAX_SEGMENTS = 20_000  # kept for drawing; later ones are counted in JobPath.omitted


class PathSegment(NamedTuple):
    """One statement's part of the path (an arc's G300 and G301 together).

    ``line`` is the statement's line (the G301's for an arc), ``first_line`` the G300's for an
    arc and ``line`` otherwise; ``text`` the source (both lines for an arc); ``points`` at
    least one, robot frame, mm; ``approximate`` for a curve that depends on unverified
    kinematics; ``note`` the planner's remark (a clamped speed, an arc planned as a line).
    """

    index: int
    kind: str
    line: int
    first_line: int
    code: str
    text: str
    points: tuple[Point, ...]
    approximate: bool = False
    note: Optional[str] = None
    loop: tuple[int, ...] = ()

    @property
    def label(self) -> str:
        """``line 12`` or ``lines 21-22``, with the repeat pass if inside a block."""
        where = f"line {self.line}" if self.first_line == self.line else f"lines {self.first_line}-{self.line}"
        if any(self.loop):
            where += f" (repeat pass {'/'.join(str(i + 1) for i in self.loop)})"
        return where

    def describe(self) -> str:
        """Everything a hover box says about the segment, one fact a line."""
        parts = [f"{self.label}: {self.text}"]
        if self.approximate:
            parts.append(f"approximate: {APPROXIMATE_NOTE}")
        if self.note:
            parts.append(f"note: {self.note}")
        return "\n".join(parts)


@dataclass(frozen=True)
class Finding:
    """A lint diagnostic and where it is drawn: its segment's end, or where the arm is when
    the job reaches its line (``segment`` None)."""

    diagnostic: object  # armctl.script.Diagnostic
    point: Point
    segment: Optional[int]

    def describe(self) -> str:
        d = self.diagnostic
        return f"line {d.span.line}:{d.span.column} {d.code} {d.severity}: {_clean(d.message)}"


@dataclass(frozen=True)
class Box:
    """The workspace box of the tool point, robot frame, mm."""

    x_mm: tuple[float, float]
    y_mm: tuple[float, float]
    z_mm: tuple[float, float]

    def edges(self) -> list[tuple[Point, Point]]:
        """The box's 12 edges."""
        corners = [(x, y, z) for x in self.x_mm for y in self.y_mm for z in self.z_mm]
        return [(a, b) for i, a in enumerate(corners) for b in corners[i + 1:]
                if sum(1 for k in range(3) if a[k] != b[k]) == 1]


@dataclass
class JobPath:
    """A job's path ready to draw."""

    file: str
    start: Point  # the tool point at the start pose
    workspace: Box
    segments: list[PathSegment] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    omitted: int = 0  # segments past max_segments: counted, not drawn (their findings sit at the path's end)
    from_line: int = 1

    @property
    def kinds(self) -> list[str]:
        """The statement kinds present, in KINDS order."""
        present = {segment.kind for segment in self.segments}
        return [kind for kind in KINDS if kind in present]

    @property
    def approximate(self) -> bool:
        return any(segment.approximate for segment in self.segments)

    def of_kind(self, kind: str) -> list[PathSegment]:
        return [segment for segment in self.segments if segment.kind == kind]

    def view_limits(self) -> tuple[tuple[float, float], ...]:
        """(low, high) of X, Y, Z that frame the job — its path, start pose and findings —
        with a margin, so a small job is not lost in its workspace box."""
        points = [self.start, *(f.point for f in self.findings), *(p for s in self.segments for p in s.points)]
        limits = []
        for k in range(3):
            low, high = min(p[k] for p in points), max(p[k] for p in points)
            pad = max(VIEW_MARGIN_MIN_MM, (high - low) * VIEW_MARGIN_SHARE)
            limits.append((low - pad, high + pad))
        return tuple(limits)


def kind_of(command) -> str:
    """The statement kind a command is drawn as: every command without a path is still."""
    return _KIND_OF.get(type(command), STILL)


def point_count(segment: Segment, arc_start: ArcStart | None = None) -> int:
    """How many points sample ``segment``: 1 without a path, 2 for a line, one per
    ARC_STEP_DEG of an arc (``arc_start`` is its G300), one per JOINT_STEP_DEG of a joint move."""
    if not segment.length or segment.kind == "still":
        return 1
    if segment.kind == "arc":
        arc = arc_through(segment.start.xyz, (arc_start.x_mm, arc_start.y_mm, arc_start.z_mm), segment.end.xyz)
        return 1 + max(2, math.ceil(math.degrees(arc.sweep_rad) / ARC_STEP_DEG - _SLACK))
    if segment.kind == "joint":
        return 1 + max(JOINT_MIN_STEPS, math.ceil(segment.length / JOINT_STEP_DEG - _SLACK))
    return 2


def sample_points(segment: Segment, count: int) -> tuple[Point, ...]:
    """``count`` points evenly spaced along the path (by the model's fraction), robot frame."""
    if count <= 1:
        return (_robot_xyz(segment.end),)
    return tuple(_robot_xyz(segment.sample(segment.time_at_fraction(k / (count - 1)))) for k in range(count))


def _robot_xyz(pose: ArmPose) -> Point:
    x, y, z = pose.robot_cartesian[:3]
    return (x, y, z)


def build_path(statements: Iterable, model: MotionModel, file: str = "<script>", diagnostics: Sequence = (), *,
               start: ArmPose | None = None, from_line: int = 1,
               max_segments: int = DEFAULT_MAX_SEGMENTS) -> JobPath:
    """Plan and sample ``statements`` (armctl.script Statements) from ``start`` (default: the
    profile's fixed pose 0, as ``estimate`` assumes) and pin ``diagnostics`` to the path."""
    planner = Planner(model, start)
    profile_box = model.profile.workspace
    path = JobPath(file, _robot_xyz(planner.pose), Box(profile_box.x_mm, profile_box.y_mm, profile_box.z_mm),
                   from_line=from_line)
    opening = None  # the G300 statement waiting for its G301
    for statement in statements:
        command = statement.command
        if len(path.segments) >= max_segments:  # counted, not planned: nothing more is drawn
            path.omitted += type(command) is not ArcStart
            continue
        arc_start = planner.pending_arc
        segment = planner.feed(command)
        if type(command) is ArcStart:
            opening = statement
            continue
        kind = kind_of(command)
        first_line, text = statement.line, _clean(statement.text)
        if kind == ARC and opening is not None:
            first_line, text = opening.line, f"{_clean(opening.text)} / {text}"
        opening = None
        points = sample_points(segment, point_count(segment, arc_start))
        path.segments.append(PathSegment(
            len(path.segments), kind, statement.line, first_line, statement.code, text, points,
            approximate=kind == JOINT, note=segment.note, loop=statement.loop,
        ))
    path.findings = place_findings(path.segments, path.start, diagnostics)
    return path


def place_findings(segments: Sequence[PathSegment], start: Point, diagnostics: Iterable) -> list[Finding]:
    """Each diagnostic at the end of the first segment of its line; for a line without one,
    where the arm is when the job reaches that line: the end of the segment before the first
    one written further down (the start pose if none is before it, the path's end if none is
    further down)."""
    first_of_line: dict[int, int] = {}
    furthest: list[int] = []  # furthest[i]: the largest first_line of segments 0…i (repeat blocks go back)
    for segment in segments:
        first_of_line.setdefault(segment.first_line, segment.index)
        first_of_line.setdefault(segment.line, segment.index)
        furthest.append(max(segment.first_line, furthest[-1] if furthest else 0))
    findings = []
    for diagnostic in diagnostics:
        line = diagnostic.span.line
        index = first_of_line.get(line)
        if index is not None:
            findings.append(Finding(diagnostic, segments[index].points[-1], index))
            continue
        later = bisect.bisect_right(furthest, line)  # the first segment written below the line
        point = segments[later - 1].points[-1] if later > 0 else start
        findings.append(Finding(diagnostic, point, None))
    return findings


def _clean(text: str) -> str:
    """A source line fit for a label: printable (undecodable bytes as U+FFFD), runs of blanks
    as one space, short."""
    text = " ".join(text.split())
    text = "".join(c if c.isprintable() and not 0xD800 <= ord(c) <= 0xDFFF else "\ufffd" for c in text)
    return text if len(text) <= MAX_TEXT_CHARS else text[: MAX_TEXT_CHARS - 1] + "…"
