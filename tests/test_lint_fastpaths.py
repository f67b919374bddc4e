"""Lint's fast paths say exactly what the slow ones say (issue 13: "findings must not change").

Three shortcuts, each held to the plain computation it replaces, which stays callable:

- ``kinematics.ball_has_solution`` proves a whole ball of poses solvable; every pose in a
  proven ball must have a solution by ``has_solution`` and by ``inverse`` (the slow path).
- ``kinematics.SolvableCells`` answers ``has_solution`` per grid cube; on random walks along
  and across the edge of the reach it must give ``has_solution``'s answer for every pose.
- ``motion.Planner.feed_s`` times a LinearMove without building its segment; it must give
  ``feed(command).duration_s`` to the bit, and leave the same pose.

And lint as a whole: the fast lint against lint with the shortcuts replaced by the slow paths
(``has_solution`` for every pose, ``feed`` for every statement), on the golden corpus and on
random walks near the workspace boundary (tests/test_lint_golden.py holds the recorded corpus).
"""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core import kinematics_regions
from armctl.core.kinematics import (
    SolvableCells, Unreachable, ball_has_solution, box_problem, forward, has_solution, inverse,
)
from armctl.host.profile import Workspace
from armctl.lint.engine import lint_lines
from armctl.core.motion import MotionModel, Planner
from armctl.host.profile import default_profile, load_profile
from armctl.script.files import iter_lines
from armctl.core.protocol import ArcEnd, ArcStart, Delay, JointMove, LinearMove, SetWorktableOrigin

ROOT = Path(__file__).resolve().parents[1]
PROFILE = default_profile()
LINKS, LIMITS, HOME = PROFILE.links, PROFILE.joint_limits_deg, PROFILE.poses[0]
NARROW = ((-120.0, 120.0), (-45.0, 80.0), (-90.0, 100.0), (-120.0, 120.0), (-110.0, 110.0), (-180.0, 180.0))
# tight wrist rolls: J4 and J6 decide, near their limits (the bound on how far they turn)
WRIST = ((-170.0, 170.0), (-90.0, 100.0), (-120.0, 120.0), (-25.0, 25.0), (-120.0, 120.0), (-40.0, 40.0))
# one branch of the closed form only (front, elbow δ > 0, J5 > 0): no other solution can hide a
# bound that is too small, so the largest proven ball touches a limit the bound must respect
ONE_BRANCH = ((-90.0, 90.0), (-60.0, 100.0), (-80.0, 99.0), (-40.0, 40.0), (1.0, 120.0), (-60.0, 60.0))
# a box that cuts through the reachable space: cubes on its faces must not be proven
SMALL_BOX = Workspace(x_mm=(-100.0, 300.0), y_mm=(-250.0, 120.0), z_mm=(40.0, 330.0), reach_mm=380.0)
_ANGLE = st.one_of(st.sampled_from([0.0, 90.0, -90.0, 180.0, 45.0]), st.floats(-180, 180))
_NEAR = st.one_of(st.sampled_from(PROFILE.poses), st.tuples(*(st.floats(-170, 170) for _ in range(6))))


def _solvable_by_inverse(pose, near, limits) -> bool:
    try:
        inverse(pose, LINKS, near, limits)
    except Unreachable:
        return False
    return True


def _ball_points(centre, radius, rng, count=60):
    """Points of the ball that a wrong bound would miss first: its surface along the axes and
    the diagonals, and random points inside and on it."""
    x, y, z = centre[:3]
    directions = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    directions += [(a, b, c) for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]
    for _ in range(count):
        directions.append(tuple(rng.gauss(0, 1) for _ in range(3)))
    for dx, dy, dz in directions:
        norm = math.sqrt(dx * dx + dy * dy + dz * dz) or 1.0
        for scale in (1.0, rng.random()):
            k = radius * scale / norm
            yield (x + dx * k, y + dy * k, z + dz * k, *centre[3:])


@settings(max_examples=300, deadline=None)
@given(
    st.floats(-450, 450), st.floats(-450, 450), st.floats(-100, 600), _ANGLE, _ANGLE, _ANGLE,
    st.floats(0.5, 60), _NEAR, st.sampled_from([LIMITS, NARROW, WRIST]), st.integers(0, 2**32 - 1),
)
def test_a_proven_ball_holds_only_solvable_poses(x, y, z, b0, b1, w, radius, near, limits, seed):
    _check_ball((x, y, z, b0, b1, w), radius, near, limits, seed)


@settings(max_examples=300, deadline=None)
@given(
    st.tuples(*(st.floats(0.0, 1.0) for _ in range(6))), st.floats(0.5, 40), _NEAR,
    st.sampled_from([LIMITS, NARROW, WRIST]), st.integers(0, 2**32 - 1),
)
def test_a_proven_ball_around_a_pose_the_arm_takes_holds_only_solvable_poses(fractions, radius, near, limits, seed):
    """Centres where the arm is (FK of joints inside the limits, often near them), so that
    most balls are proven and a bound too small shows as a pose on the surface that fails."""
    joints = [low + (high - low) * f for f, (low, high) in zip(fractions, limits)]
    _check_ball(tuple(forward(joints, LINKS)), radius, near, limits, seed)


@settings(max_examples=100, deadline=None)
@given(
    st.tuples(*(st.floats(0.05, 0.95) for _ in range(6))), _NEAR,
    st.sampled_from([LIMITS, NARROW, WRIST, ONE_BRANCH, ONE_BRANCH]), st.integers(0, 2**32 - 1),
)
def test_the_largest_proven_ball_is_still_sound(fractions, near, limits, seed):
    """At the largest radius the proof allows, some joint's whole interval touches its limit:
    there a bound that were too small would let a pose on the surface through."""
    joints = [low + (high - low) * f for f, (low, high) in zip(fractions, limits)]
    centre = tuple(forward(joints, LINKS))
    low, high = 0.0, 80.0
    if not ball_has_solution(centre, 0.01, LINKS, near, limits):
        return
    for _ in range(16):
        middle = (low + high) / 2
        low, high = (middle, high) if ball_has_solution(centre, middle, LINKS, near, limits) else (low, middle)
    _check_ball(centre, low, near, limits, seed, directions=240)


def _check_ball(centre, radius, near, limits, seed, directions=60):
    if not ball_has_solution(centre, radius, LINKS, near, limits):
        return
    rng = random.Random(seed)
    for pose in [centre, *_ball_points(centre, radius, rng, directions)]:
        assert has_solution(pose, LINKS, near, limits), pose
        assert _solvable_by_inverse(pose, near, limits), pose


def test_balls_are_proven_inside_the_reach_and_not_across_its_edge():
    down = (180.0, 0.0, 0.0)
    assert ball_has_solution((220.0, 0.0, 150.0, *down), 14.0, LINKS, HOME, LIMITS)  # the benchmark's walk
    assert ball_has_solution((250.0, -100.0, 100.0, 180.0, 20.0, 30.0), 5.0, LINKS, HOME, LIMITS)
    # a ball that holds an unreachable pose is never proven
    for centre in [(440.0, 0.0, 150.0, *down), (0.0, 0.0, 300.0, *down), (300.0, 0.0, 150.0, 0.0, 0.0, 0.0)]:
        points = [centre, *_ball_points(centre, 30.0, random.Random(1))]
        assert not all(has_solution(p, LINKS, HOME, LIMITS) for p in points)
        assert not ball_has_solution(centre, 30.0, LINKS, HOME, LIMITS)


def _boundary_walk(rng, steps, attitudes):
    """Poses wandering in and out of the reach: along the outer sphere, near the base axis,
    near the joint limits, with attitudes that change now and then."""
    x, y, z = rng.uniform(-300, 300), rng.uniform(-300, 300), rng.uniform(0, 450)
    attitude = rng.choice(attitudes)
    for _ in range(steps):
        if rng.random() < 0.05:
            attitude = rng.choice(attitudes)
        if rng.random() < 0.1:  # jump: inside the reach, onto its outer edge or just beyond it
            bearing, elevation = rng.uniform(-math.pi, math.pi), rng.uniform(-0.5, 1.3)
            radius = rng.choice([rng.uniform(120, 380), rng.uniform(380, 470)])
            x, y = radius * math.cos(elevation) * math.cos(bearing), radius * math.cos(elevation) * math.sin(bearing)
            z = 150 + radius * math.sin(elevation)
        else:
            x, y, z = x + rng.uniform(-12, 12), y + rng.uniform(-12, 12), z + rng.uniform(-12, 12)
        yield (x, y, z, *attitude)


@pytest.mark.parametrize("cell_mm", [4.0, 16.0, 40.0])
@pytest.mark.parametrize("limits", [LIMITS, NARROW, WRIST], ids=["default", "narrow", "wrist"])
@pytest.mark.parametrize("box", [None, PROFILE.workspace, SMALL_BOX], ids=["no box", "box", "small box"])
def test_solvable_cells_answer_as_has_solution_on_walks_across_the_edge(monkeypatch, cell_mm, limits, box):
    proofs = []
    monkeypatch.setattr(kinematics_regions, "ball_has_solution",
                        lambda *args: proofs.append(ball_has_solution(*args)) or proofs[-1])
    rng = random.Random(int(cell_mm) * 7 + len(limits[0]))
    attitudes = [(180.0, 0.0, 0.0), (180.0, 0.0, 45.0), (150.0, 20.0, -30.0), (90.0, 0.0, 0.0), (180.0, 89.0, 0.0),
                 (180.0, 0.0, 20.0), (170.0, -10.0, -15.0)]
    cells = SolvableCells(LINKS, limits, box, cell_mm=cell_mm, max_cells=500)
    answers = {True: 0, False: 0}
    for pose in _boundary_walk(rng, 3000, attitudes):
        near = HOME if rng.random() < 0.8 else PROFILE.poses[rng.randrange(4)]
        expected = (box is None or box_problem(pose[:3], box) is None) and has_solution(pose, LINKS, near, limits)
        assert cells(pose, near) is expected, pose
        if cells.proven(pose, near):
            assert expected, pose
        answers[expected] += 1
    assert answers[True] > 30 and answers[False] > 100  # the walk does cross the edge
    assert len(proofs) > 100  # cubes were tried (the table refilled on the way)
    assert any(proofs) or cell_mm > 16  # and proven, unless too large for the tight limits


# --- Planner.feed_s is feed(...).duration_s -----------------------------------------------------

_POINT = st.tuples(st.floats(-300, 300), st.floats(-300, 300), st.floats(-50, 400))


@st.composite
def _commands(draw):
    kind = draw(st.sampled_from(["line", "line", "line", "same", "joint", "delay", "arc", "origin"]))
    attitude = draw(st.sampled_from([(180.0, 0.0, 0.0), (180.0, 0.0, 90.0), (170.0, 10.0, -20.0)]))
    pwm = draw(st.sampled_from([1000.0, 1500.0, 2000.0]))
    speed = draw(st.sampled_from([30.0, 600.0, 3000.0, 6000.0, 9000.0]))
    e = draw(st.sampled_from([(0.0, 0.0), (0.0, 0.0), (15.0, -5.0)]))
    if kind == "line":
        return [LinearMove(*draw(_POINT), *attitude, pwm_us=pwm, speed_mm_min=speed, e0_deg=e[0], e1_deg=e[1],
                           pwm_channel=draw(st.integers(1, 4)))]
    if kind == "same":  # a gripper-, attitude- or E-only line
        return [LinearMove(250.0, 0.0, 150.0, *attitude, pwm_us=pwm, speed_mm_min=speed, e0_deg=e[0], e1_deg=e[1])]
    if kind == "joint":
        return [JointMove(*draw(st.tuples(*(st.floats(-60, 60) for _ in range(6)))), pwm_us=pwm, speed_deg_s=60.0)]
    if kind == "delay":
        return [Delay(draw(st.sampled_from([0.0, 250.0])))]
    if kind == "origin":
        return [SetWorktableOrigin(*draw(_POINT))]
    return [ArcStart(*draw(_POINT), *attitude, pwm_us=pwm, radius_mm=50.0, speed_mm_min=speed),
            ArcEnd(*draw(_POINT), *attitude, pwm_us=pwm, speed_mm_min=speed)]


@settings(max_examples=150, deadline=None)
@given(st.lists(_commands(), min_size=1, max_size=25), st.sampled_from([None, 0.7, 1.3]))
def test_feed_s_is_feed_duration_to_the_bit(batches, speed_factor):
    model = MotionModel(PROFILE, speed_factor=speed_factor)
    slow, fast = Planner(model), Planner(model)
    for batch in batches:
        for command in batch:
            assert fast.feed_s(command) == slow.feed(command).duration_s
            if isinstance(command, ArcStart):
                assert fast.pending_arc is command
    assert fast.pose == slow.pose
    assert fast.pose.known_joints == slow.pose.known_joints  # the IK hint carried along a chain of lines
    assert fast.pose.origin_mm == slow.pose.origin_mm


# --- lint as a whole: fast against slow ---------------------------------------------------------


def _slow_lint(monkeypatch, *args, **kwargs):
    """lint_lines with the shortcuts replaced by the plain computations they stand for."""
    with monkeypatch.context() as patch:
        patch.setattr(SolvableCells, "proven", lambda self, pose, near: False)  # every target by box_problem and has_solution
        patch.setattr(Planner, "feed_s", lambda self, command: self.feed(command).duration_s)
        patch.setattr(kinematics_regions, "ball_has_solution", lambda *a: pytest.fail("the slow lint proved a cube"))
        return lint_lines(*args, **kwargs)


def _fast_and_slow(monkeypatch, lines, name, profile, **options):
    """``lint_lines`` of ``lines`` as it runs, and as ``_slow_lint`` runs it."""
    return (lint_lines(iter(lines), name, profile, **options),
            _slow_lint(monkeypatch, iter(lines), name, profile, **options))


def _found(report):
    return (report.errors, report.warnings, report.hidden,
            [(d.span.line, d.span.column, d.code, d.severity, d.message, d.hint) for d in report.diagnostics])


def _walk_script(seed: int, steps: int) -> list[str]:
    """A script near and across the workspace boundary: G1 walks, G91 loops, G54 origins,
    G6 joint hints and POSE (so the IK hint changes), attitude changes, arcs."""
    rng = random.Random(seed)
    attitudes = [(180.0, 0.0, 0.0), (180.0, 0.0, 60.0), (150.0, 25.0, -40.0), (90.0, 0.0, 0.0)]
    lines = ["G1 X250 Y0 Z150 A180 B0 C0 F6000 S1000"]
    for pose in _boundary_walk(rng, steps, attitudes):
        roll = rng.random()
        if roll < 0.03:
            lines.append(f"G54 X{rng.uniform(-60, 60):.1f} Y{rng.uniform(-60, 60):.1f} Z{rng.uniform(-30, 30):.1f}")
        elif roll < 0.06:
            lines.append("G6 " + " ".join(f"J{k}={rng.uniform(-50, 50):.1f}" for k in range(1, 7)) + " F60")
        elif roll < 0.08:
            lines.append(f"POSE {rng.randrange(4)}")
        elif roll < 0.10:
            lines += ["G91", "o1 repeat [3]", f"G1 X{rng.uniform(-80, 80):.1f} Y{rng.uniform(-80, 80):.1f}",
                      "o1 endrepeat", "G90"]
        elif roll < 0.12:
            lines += [f"G300 X{pose[0] + 20:.2f} Y{pose[1] + 20:.2f} Z{pose[2]:.2f} R20",
                      f"G301 X{pose[0] + 40:.2f} Y{pose[1]:.2f} Z{pose[2]:.2f}"]
        else:
            x, y, z, a, b, c = pose
            lines.append(f"G1 X{x:.2f} Y{y:.2f} Z{z:.2f} A{a:g} B{b:g} C{c:g}")
    return lines


@pytest.mark.parametrize("seed", range(4))
def test_fast_lint_is_slow_lint_on_walks_near_the_boundary(monkeypatch, seed):
    lines = _walk_script(seed, 600)
    fast, slow = _fast_and_slow(monkeypatch, lines, "walk.txt", PROFILE, max_diagnostics=1_000_000)
    assert _found(fast) == _found(slow)
    assert sum(1 for d in fast.diagnostics if d.code == "L103") > 20  # the walk does leave the reach


@pytest.mark.parametrize("script, profile", [
    ("tests/data/lint/every_rule.txt", "tests/data/lint/profile.toml"),
    ("tests/data/lint/golden/geometry.txt", None),
    *((f"scripts/{path.name}", None) for path in sorted((ROOT / "scripts").glob("*.txt"))),
])
def test_fast_lint_is_slow_lint_on_the_corpus(monkeypatch, script, profile):
    chosen = PROFILE if profile is None else load_profile(ROOT / profile)
    with open(ROOT / script, "rb") as stream:  # as lint reads a file (every_rule.txt is not all UTF-8)
        lines = list(iter_lines(stream, name=script))
    fast, slow = _fast_and_slow(monkeypatch, lines, script, chosen, max_diagnostics=1_000_000)
    assert _found(fast) == _found(slow)
    assert fast.diagnostics or script.startswith("scripts/")  # the lint corpus does find things


def test_a_long_job_crosses_the_motion_bound_at_the_same_statement(monkeypatch):
    """E012 from feed_s's sums: 24 h of slow moves back and forth, then more."""
    lines = ["G1 X200 Y0 Z150 A180 B0 C0 F60 S1000"]
    lines += [f"G1 X{200 + 100 * (k % 2)} Y0 Z150" for k in range(1, 900)]
    lines += ["o1 repeat [2000]", "G1 X300 Y0 Z150", "G1 X200 Y0 Z150", "o1 endrepeat", "G1 X250 Y0 Z150"]
    fast, slow = _fast_and_slow(monkeypatch, lines, "long.txt", PROFILE)
    assert [d.code for d in fast.diagnostics if d.code == "E012"] == ["E012"]
    assert _found(fast) == _found(slow)


def _expression_script(seed: int, steps: int) -> list[str]:
    """``_walk_script``'s walk written with parameters and expressions (as benchmarks/cli_speed.py's
    expression rows): each G1 target assigned to #<x> #<y> #<z>, then reached through brackets."""
    lines = ["#<x> = 250", "#<y> = 0", "#<z> = 150", "#<Spare> = 1"]
    for line in _walk_script(seed, steps):
        if line.startswith("G1 X") and " Z" in line:
            words = dict((word[0], word[1:]) for word in line.split()[1:])
            lines += [f"#<x> = [{words['X']} - 0.5]", f"#<y> = {words['Y']}", f"#<Z> = [{words['Z']} + 0]",
                      f"G1 X[#<x> + 0.5] Y#<y> Z[#<z> * 1]" + "".join(f" {k}{v}" for k, v in words.items() if k not in "XYZ")
                      + f" (step {len(lines)})"]
        else:
            lines.append(line)
    return lines


@pytest.mark.parametrize("seed", range(2))
def test_fast_lint_is_slow_lint_on_expression_walks(monkeypatch, seed):
    lines = _expression_script(seed, 300)
    fast, slow = _fast_and_slow(monkeypatch, lines, "expr.txt", PROFILE, max_diagnostics=1_000_000)
    assert _found(fast) == _found(slow)
    codes = {d.code for d in fast.diagnostics}
    assert "L103" in codes and "L401" in codes  # the walk leaves the reach; #<Spare> is never read
