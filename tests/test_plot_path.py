"""The pure half of ``armctl plot``: a compiled job → segments of points, kinds, lines, findings.

No plotting library is needed here.  Expected geometry is computed independently of the
motion model: the circle through three points by the textbook circumcentre formula, a joint
move's curve by forward kinematics of joints interpolated by hand.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from armctl.lint.engine import lint_lines
from armctl.core.motion import MotionModel
from armctl.plot.path import (
    APPROXIMATE_NOTE, ARC_STEP_DEG, JOINT_MIN_STEPS, JOINT_STEP_DEG, KINDS, build_path, place_findings,
)
from armctl.plot.style import KIND_COLORS
from armctl.host.profile import default_profile
from armctl.script import compile_file, compile_text

ROOT = Path(__file__).resolve().parents[1]
PROFILE = default_profile()
MODEL = MotionModel(PROFILE)
HOME = "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F30"  # fixed pose 0 itself: no motion
FIRST = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000"


def path_of(text: str, diagnostics=(), **options):
    compilation = compile_text(text, "job.txt", **{k: v for k, v in options.items() if k == "from_line"})
    path = build_path(compilation, MODEL, "job.txt", diagnostics,
                      **{k: v for k, v in options.items() if k != "from_line"})
    assert compilation.error_count == 0 or diagnostics, compilation.diagnostics
    return path


def close(a, b, tol=1e-6):
    return all(abs(p - q) <= tol for p, q in zip(a, b))


def sub(a, b):
    return tuple(p - q for p, q in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(p * q for p, q in zip(a, b))


def circumcentre(a, b, c):
    """Centre of the circle through three points (u = b − a, v = c − a, w = u × v)."""
    u, v = sub(b, a), sub(c, a)
    w = cross(u, v)
    num = tuple(dot(u, u) * p + dot(v, v) * q for p, q in zip(cross(v, w), cross(w, u)))
    return tuple(a[i] + num[i] / (2 * dot(w, w)) for i in range(3))


# --- the example job --------------------------------------------------------------------------------


def test_square_and_circle_segments_lines_kinds_and_point_counts():
    path = build_path(compile_file(ROOT / "scripts/draw_square_circle.txt"), MODEL, "draw")
    summary = [(s.kind, s.first_line, s.line, len(s.points)) for s in path.segments]
    lines = [(10, 2), (13, 2), (14, 2), (15, 2), (16, 2), (17, 2), (18, 2), (19, 2), (22, 2), (23, 2)]
    assert summary[:10] == [("linear", line, line, n) for line, n in lines]
    # two half circles: 180° / 5° = 36 chords each, the G300 and G301 lines together
    assert summary[10:12] == [("arc", 24, 25, 37), ("arc", 26, 27, 37)]
    assert summary[12] == ("linear", 28, 28, 2)
    assert summary[13][:3] == ("joint", 30, 30)  # POSE 0, through forward kinematics
    assert path.kinds == ["linear", "arc", "joint"]
    # the square's corners, in order, at Z20
    corners = [s.points[-1] for s in path.segments[2:7]]
    assert [tuple(round(v, 6) for v in p) for p in corners] == [
        (210, -40, 20), (290, -40, 20), (290, 40, 20), (210, 40, 20), (210, -40, 20)]


def test_the_start_is_the_profiles_fixed_pose_0():
    path = path_of(FIRST)
    assert close(path.start, PROFILE.kinematics.forward(PROFILE.poses[0])[:3])
    assert close(path.segments[0].points[0], path.start)


# --- point counts -------------------------------------------------------------------------------------


@pytest.mark.parametrize("line, count", [
    ("G6 J1=60", 1 + 60 / JOINT_STEP_DEG),  # 30 chords
    ("G6 J1=1", 1 + JOINT_MIN_STEPS),  # a short joint move still gets its minimum
    ("G6 J1=10 J2=16", 1 + 16 / JOINT_STEP_DEG),  # the lead joint sets the count
    ("G6 S2000", 1),  # PWM only: no path
    ("G4 P100", 1),
    ("M3", 1),
    ("POSE 0", 1),  # already there
])
def test_joint_and_still_point_counts(line, count):
    path = path_of(f"{HOME}\n{line}\n")
    assert len(path.segments[1].points) == count


@pytest.mark.parametrize("text, count", [
    (f"{FIRST}\nG1 X300", 2),
    (f"{FIRST}\nG1 S2000", 1),  # PWM only: one point, it does not move
    (f"{FIRST}\nG220 X300 K500 F3000", 2),
    # from (250, 0): a quarter circle about (220, 0) (90° / 5° = 18 chords); a half circle and
    # three quarters about (280, 0) (36 and 54 chords); a 7° arc about (220, 0) (2 chords at least)
    (f"{FIRST}\nG300 X{220 + 30 * math.cos(math.pi / 4)} Y{30 * math.sin(math.pi / 4)} R30 F900\nG301 X220 Y30", 19),
    (f"{FIRST}\nG300 X280 Y30 R30 F900\nG301 X310 Y0", 37),
    (f"{FIRST}\nG300 X280 Y30 R30 F900\nG301 X280 Y-30", 1 + 54),
    (f"{FIRST}\nG300 X{220 + 30 * math.cos(math.radians(3.5))} Y{30 * math.sin(math.radians(3.5))} R30 F900\n"
     f"G301 X{220 + 30 * math.cos(math.radians(7))} Y{30 * math.sin(math.radians(7))}", 3),
])
def test_cartesian_point_counts(text, count):
    path = path_of(text)
    assert len(path.segments[-1].points) == count
    assert path.segments[-1].note is None  # the arcs above are true to their R30
    assert ARC_STEP_DEG == 5.0  # the counts above are written for it


# --- geometry -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("start, via, end", [
    ((280, 0, 20), (250, 30, 20), (220, 0, 20)),  # the example's half circle, flat
    ((250, 0, 100), (250, 30, 130), (250, 0, 160)),  # in the Y/Z plane
    ((200, -50, 100), (260, 10, 180), (300, 60, 120)),  # tilted, less than a half
    ((200, 0, 100), (230, 40, 120), (205, 5, 101)),  # more than a half
])
def test_arc_points_lie_on_the_circle_through_the_three_points(start, via, end):
    text = (f"G1 X{start[0]} Y{start[1]} Z{start[2]} A180 B0 C0 S1000 F3000\n"
            f"G300 X{via[0]} Y{via[1]} Z{via[2]} R30 F900\nG301 X{end[0]} Y{end[1]} Z{end[2]}\n")
    _check_arc(path_of(text).segments[-1], start, via, end)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(*[st.integers(-300, 300)] * 3), min_size=3, max_size=3, unique=True))
@example([(-3, -38, 0), (7, 83, -5), (-1, -27, -1)])  # a wide arc: the sag bound needs the true step angle
def test_any_arc_is_sampled_on_its_circle(points):
    start, via, end = points
    u, v = sub(via, start), sub(end, start)
    w = cross(u, v)
    if math.sqrt(dot(w, w)) / max(math.dist(start, via), math.dist(start, end), math.dist(via, end)) < 1.0:
        return  # (nearly) collinear: planned as a straight line, with a note
    _check_arc(path_of(f"G1 X{start[0]} Y{start[1]} Z{start[2]} A180 B0 C0 S1000 F3000\n"
                       f"G300 X{via[0]} Y{via[1]} Z{via[2]} R30 F900\nG301 X{end[0]} Y{end[1]} Z{end[2]}\n").segments[-1],
               start, via, end)


def _check_arc(segment, start, via, end):
    assert segment.kind == "arc"
    centre = circumcentre(start, via, end)
    radius = math.dist(centre, start)
    normal = cross(sub(via, start), sub(end, start))
    points = segment.points
    assert close(points[0], start) and close(points[-1], end)
    for p in points:
        assert abs(math.dist(p, centre) - radius) <= 1e-6 * max(1.0, radius)
        assert abs(dot(sub(p, centre), normal)) / math.sqrt(dot(normal, normal)) <= 1e-6 * max(1.0, radius)
    chords = [math.dist(a, b) for a, b in zip(points, points[1:])]
    assert max(chords) - min(chords) <= 1e-6 * max(1.0, radius)  # evenly spaced along the arc
    # the arc goes through the G300 point, not round the other side: the via point is within one
    # chord's sag of the polyline
    step = 2 * math.asin(min(1.0, chords[0] / (2 * radius)))  # radians between samples
    sag = radius * (1 - math.cos(step / 2))
    nearest = min(_distance_to_chord(via, a, b) for a, b in zip(points, points[1:]))
    assert nearest <= sag + 1e-6


def _distance_to_chord(p, a, b):
    d = sub(b, a)
    t = min(max(dot(sub(p, a), d) / dot(d, d), 0.0), 1.0)
    return math.dist(p, tuple(a[i] + d[i] * t for i in range(3)))


def test_a_joint_moves_points_are_forward_kinematics_of_interpolated_joints():
    path = path_of(f"{HOME}\nG6 J1=60 J2=30 J3=-20 J5=45 F45\n")
    segment = path.segments[1]
    q0, q1 = (0, 0, 0, 0, 90, 0), (60, 30, -20, 0, 45, 0)
    count = len(segment.points)
    assert count == 31  # lead joint 60° / 2°
    for k, point in enumerate(segment.points):
        joints = [a + (b - a) * k / (count - 1) for a, b in zip(q0, q1)]
        assert close(point, PROFILE.kinematics.forward(joints)[:3], 1e-9)
    assert segment.approximate and APPROXIMATE_NOTE in segment.describe()
    assert not path_of(FIRST).segments[0].approximate  # Cartesian paths do not depend on the kinematics


def test_points_are_in_the_robot_frame_after_g54():
    path = path_of(f"G54 X10 Y-5 Z0\n{FIRST}\n")
    assert close(path.segments[-1].points[-1], (260, -5, 150))


# --- labels, kinds, loops -------------------------------------------------------------------------------


def test_every_segment_carries_its_line_kind_and_text():
    path = path_of(f"{FIRST}\nG220 X300 K500 F9000 ; fast\nG4 P100\nG300 X330 Y30 R30 F900\nG301 X360 Y0\n")
    assert [(s.kind, s.label, s.code) for s in path.segments] == [
        ("linear", "line 1", "G1"), ("accel", "line 2", "G220"), ("still", "line 3", "G4"), ("arc", "lines 4-5", "G301")]
    assert path.segments[1].text == "G220 X300 K500 F9000 ; fast"
    assert "clamped" in path.segments[1].describe()  # the planner's note travels with the segment
    assert path.segments[3].text == "G300 X330 Y30 R30 F900 / G301 X360 Y0"


def test_a_repeat_block_draws_each_pass():
    path = path_of(f"{FIRST}\nO100 repeat [2]\nG91\nG1 X10\nG90\nO100 endrepeat\n")
    assert [s.label for s in path.segments] == ["line 1", "line 4", "line 4 (repeat pass 2)"]
    assert close(path.segments[-1].points[-1], (270, 0, 150))


def test_from_line_draws_the_rest_from_the_fixed_pose_0():
    path = path_of(f"{FIRST}\nG1 X300\nG1 Y50\n", from_line=3)
    assert [s.line for s in path.segments] == [3]
    assert close(path.segments[0].points[0], path.start) and close(path.segments[0].points[-1], (300, 50, 150))


def test_segments_past_the_cap_are_counted_not_kept():
    text = f"{FIRST}\n" + "".join(f"G1 X{250 + k}\n" for k in range(1, 10)) + "G300 X280 Y30 R30 F900\nG301 X310 Y0\n"
    late = SimpleNamespace(span=SimpleNamespace(line=12))  # the G301, past the cap
    path = path_of(text, [late], max_segments=4)
    assert len(path.segments) == 4 and path.omitted == 6 + 1  # an arc is one segment
    assert path.findings[0].segment is None and path.findings[0].point == path.segments[-1].points[-1]


def test_every_kind_has_a_colour():
    assert set(KIND_COLORS) == set(KINDS)


# --- findings ----------------------------------------------------------------------------------------------


def test_findings_are_pinned_to_their_segment_or_to_where_the_arm_is():
    text = f"{FIRST}\n#<unused> = 5\nG1 X500\nG1 Q5\nG4 P100\n"
    report = lint_lines(text.splitlines(), "job.txt", PROFILE)
    assert [(d.span.line, d.code) for d in report.diagnostics] == [(2, "L401"), (3, "L103"), (4, "E002")]
    path = path_of(text, report.diagnostics)
    by_code = {f.diagnostic.code: f for f in path.findings}
    line3 = next(s for s in path.segments if s.line == 3)
    assert by_code["L103"].segment == line3.index and by_code["L103"].point == line3.points[-1] == (500, 0, 150)
    # a comment-like line and a line with errors move nothing: where the arm is when the job gets there
    assert by_code["L401"].segment is None and close(by_code["L401"].point, (250, 0, 150))
    assert by_code["E002"].segment is None and close(by_code["E002"].point, (500, 0, 150))
    assert "line 3:4 L103 warning" in by_code["L103"].describe()  # the built-in profile's workspace: illustrative


def test_findings_before_the_first_and_after_the_last_segment():
    path = path_of(f"\n{FIRST}\nG1 X300\n")
    finding = lambda line: SimpleNamespace(span=SimpleNamespace(line=line))  # noqa: E731
    placed = place_findings(path.segments, path.start, [finding(1), finding(2), finding(3), finding(9)])
    assert [(f.segment, f.point) for f in placed] == [
        (None, path.start), (0, path.segments[0].points[-1]), (1, (300, 0, 150)), (None, (300, 0, 150))]


def test_a_finding_inside_a_repeat_block_without_a_segment_is_placed_after_its_last_pass():
    path = path_of(f"{FIRST}\nO100 repeat [2]\nG91\nG1 X10\nG90\nO100 endrepeat\nG1 Y10\n")
    placed = place_findings(path.segments, path.start, [SimpleNamespace(span=SimpleNamespace(line=5))])
    assert placed[0].segment is None and close(placed[0].point, (270, 0, 150))


def test_a_finding_on_a_g300_line_belongs_to_its_arc():
    path = path_of(f"{FIRST}\nG300 X280 Y30 R30 F900\nG301 X310 Y0\n")
    placed = place_findings(path.segments, path.start, [SimpleNamespace(span=SimpleNamespace(line=2))])
    assert placed[0].segment == 1 and placed[0].point == path.segments[1].points[-1]


# --- purity ------------------------------------------------------------------------------------------------


def test_the_sampling_imports_no_plotting_and_no_io():
    code = ("import sys, armctl.plot.path, armctl.plot.style\n"
            "print(sorted(m for m in ('plotly', 'matplotlib', 'click', 'rich', 'serial', 'threading', 'socket')"
            " if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
