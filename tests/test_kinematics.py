"""Kinematics: the documented conventions by example, and FK/IK round trips by Hypothesis."""

import math

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from armctl.core.kinematics import (
    CartesianPose, Kinematics, Links, Unreachable, forward, has_solution, inverse, reach_problem, reachable, rotation_matrix,
    solutions, wrap_deg,
)
from armctl.core.kinematics_inverse import _fit
from armctl.host.profile import parse_profile

LINKS = Links(base_height_mm=150, shoulder_offset_mm=30, upper_arm_mm=180, elbow_offset_mm=30, forearm_mm=180,
              tool_mm=60)
LIMITS = ((-170, 170), (-90, 100), (-120, 120), (-180, 180), (-120, 120), (-360, 360))


def assert_same_pose(a, b, mm=1e-6, rot=1e-9):
    assert max(abs(p - q) for p, q in zip(a[:3], b[:3])) <= mm, (a, b)
    ra, rb = rotation_matrix(*a[3:]), rotation_matrix(*b[3:])
    assert max(abs(p - q) for p, q in zip(ra, rb)) <= rot, (a, b)


# --- conventions, by example -------------------------------------------------------------------


def test_home_pose_points_the_tool_straight_down():
    # J2 = J3 = 0: upper arm vertical, forearm horizontal; J5 = 90 bends the flange down.
    pose = forward((0, 0, 0, 0, 90, 0), LINKS)
    assert pose[:3] == pytest.approx((30 + 180, 0, 150 + 180 + 30 - 60), abs=1e-9)
    assert_same_pose(pose, (210, 0, 300, 180, 0, 0))
    assert pose.b0_deg == pytest.approx(180) and pose.w_deg == pytest.approx(0, abs=1e-9)


def test_all_zero_joints_point_the_tool_forward():
    pose = forward((0,) * 6, LINKS)
    assert pose[:3] == pytest.approx((30 + 180 + 60, 0, 150 + 180 + 30), abs=1e-9)
    assert pose.b1_deg == pytest.approx(-90)  # tool z along +X: pitch −90 in the roll-pitch-yaw convention


def test_base_yaw_turns_position_and_yaw_together():
    pose = forward((90, 0, 0, 0, 90, 0), LINKS)
    assert pose[:3] == pytest.approx((0, 210, 300), abs=1e-9)
    assert_same_pose(pose, (0, 210, 300, 180, 0, 90))


def test_positive_shoulder_leans_forward_and_positive_elbow_tilts_down():
    assert forward((0, 10, 0, 0, 90, 0), LINKS).x_mm > 210
    assert forward((0, 0, 10, 0, 90, 0), LINKS).z_mm < 300


def test_flange_roll_turns_the_tool_about_its_axis():
    # Tool down (J5 = 90): J6 = −90 turns the tool to W = +90 without moving the tool point.
    pose = forward((0, 0, 0, 0, 90, -90), LINKS)
    assert_same_pose(pose, (210, 0, 300, 180, 0, 90))


def test_wrap_deg_is_half_open():
    assert wrap_deg(180) == 180 and wrap_deg(-180) == 180 and wrap_deg(540) == 180 and wrap_deg(-190) == 170


# --- inverse ----------------------------------------------------------------------------------


def test_inverse_of_home_is_home():
    assert inverse((210, 0, 300, 180, 0, 0), LINKS, near=(0, 0, 0, 0, 90, 0)) == pytest.approx((0, 0, 0, 0, 90, 0), abs=1e-7)


def test_inverse_picks_the_solution_nearest_the_hint():
    pose = forward((20, -10, 80, 10, 50, 5), LINKS)  # wrist centre near the base: reachable both ways
    candidates = solutions(pose, LINKS)
    assert len(candidates) == 8  # front/back × elbow up/down × wrist flip
    assert len(solutions(forward((20, 40, -30, 10, 50, 5), LINKS), LINKS)) == 4  # too far to reach backwards
    for candidate in candidates:
        assert inverse(pose, LINKS, near=candidate) == pytest.approx(candidate, abs=1e-6)


def test_inverse_moves_angles_by_whole_turns_towards_the_hint():
    pose = forward((0, 0, 0, 0, 90, 200), LINKS)
    assert inverse(pose, LINKS, near=(0, 0, 0, 0, 90, 190))[5] == pytest.approx(200)
    assert inverse(pose, LINKS, near=(0, 0, 0, 0, 90, -150))[5] == pytest.approx(-160)


def test_wrist_singularity_keeps_the_hinted_forearm_roll():
    pose = forward((0, 20, 10, 30, 0, 15), LINKS)  # J5 = 0: only J4 + J6 matters
    joints = inverse(pose, LINKS, near=(0, 20, 10, 12, 0, 0))
    assert joints[3] == pytest.approx(12) and joints[4] == pytest.approx(0, abs=1e-6)
    assert_same_pose(forward(joints, LINKS), pose)


def test_out_of_reach_raises_unreachable():
    with pytest.raises(Unreachable, match="out of the arm's reach"):
        inverse((1000, 0, 0, 180, 0, 0), LINKS)


def test_joint_limits_are_honoured_or_named():
    pose = forward((0, 0, 0, 0, 90, 0), LINKS)
    tight = list(LIMITS)
    tight[4] = (-30, 30)  # every solution needs |J5| ≥ 90 or a flipped wrist outside the limits
    with pytest.raises(Unreachable, match=r"J\d = .* outside its limits"):
        inverse(pose, LINKS, limits=tight)


def test_kinematics_bundle_uses_home_as_hint():
    kin = Kinematics(LINKS, LIMITS, home=(0, 0, 0, 0, 90, 0))
    assert kin.inverse(kin.forward((0, 0, 0, 0, 90, 0))) == pytest.approx((0, 0, 0, 0, 90, 0), abs=1e-7)


# --- properties ---------------------------------------------------------------------------------

@settings(max_examples=300, deadline=None)
@given(st.tuples(*(st.floats(0.02, 0.98) for _ in range(6))))
def test_ik_of_fk_reproduces_joints_inside_limits_away_from_singularities(fractions):
    joints = tuple(low + (high - low) * f for (low, high), f in zip(LIMITS, fractions))
    joints = joints[:5] + (max(-170.0, min(170.0, joints[5])),)  # one turn of J6, so the answer is unique
    assume(abs(math.sin(math.radians(joints[4]))) > 0.05)  # wrist singularity J5 = 0
    assume(abs(math.sin(math.radians(joints[2]) - math.atan2(30, 180))) > 0.05)  # elbow stretched
    pose = forward(joints, LINKS)
    assume(math.hypot(pose.x_mm, pose.y_mm) > 1)
    found = inverse(pose, LINKS, near=joints, limits=LIMITS)
    assert_same_pose(forward(found, LINKS), pose)
    assert found == pytest.approx(joints, abs=1e-6)


@settings(max_examples=300, deadline=None)
@given(
    st.floats(120, 330), st.floats(-180, 180), st.floats(0, 300),
    st.floats(-30, 30), st.floats(-30, 30), st.floats(-180, 180),
)
def test_fk_of_ik_reproduces_poses_over_the_reachable_workspace(radius, bearing, z, tilt_x, tilt_y, yaw):
    x, y = radius * math.cos(math.radians(bearing)), radius * math.sin(math.radians(bearing))
    pose = (x, y, z, 180 + tilt_x, tilt_y, yaw)  # tool roughly down: the arm's working attitudes
    try:
        joints = inverse(pose, LINKS, near=(0, 0, 0, 0, 90, 0), limits=LIMITS)
    except Unreachable:
        assume(False)
    assert all(low - 1e-9 <= j <= high + 1e-9 for j, (low, high) in zip(joints, LIMITS))
    assert_same_pose(forward(joints, LINKS), pose)


# --- reachability (lint) --------------------------------------------------------------------------


PROFILE = parse_profile({"links": {"base_height_mm": 150, "shoulder_offset_mm": 30, "upper_arm_mm": 180,
                                   "elbow_offset_mm": 30, "forearm_mm": 180, "tool_mm": 60}})


def test_reachable_inside_workspace():
    assert reachable((250, 0, 150, 180, 0, 0), PROFILE)
    assert reach_problem((250, 0, 150, 180, 0, 0), PROFILE) is None


def test_reachable_names_the_problem():
    assert "workspace" in reach_problem((250, 0, -100, 180, 0, 0), PROFILE)
    assert "reach radius" in reach_problem((400, 0, 300, 180, 0, 0), PROFILE)
    assert "reach" in reach_problem((0, 0, 550, 180, 0, 0), PROFILE)
    assert not reachable((400, 0, 300, 180, 0, 0), PROFILE)


def test_reachable_applies_the_worktable_origin():
    assert reachable((0, 0, 0, 180, 0, 0), PROFILE, origin_mm=(250, 0, 150))
    assert not reachable((0, 0, 0, 180, 0, 0), PROFILE, origin_mm=(0, 0, -100))


def test_cartesian_pose_fields_carry_units():
    assert CartesianPose(1, 2, 3, 4, 5, 6)._fields == ("x_mm", "y_mm", "z_mm", "b0_deg", "b1_deg", "w_deg")


# --- has_solution: lint's fast reach test is inverse's answer (issue 13) ---------------------

HOME = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)
POSES = [HOME, (0.0, 30.0, 30.0, 0.0, 30.0, 0.0), (90.0, 0.0, 0.0, 0.0, 90.0, 0.0), (0.0, -45.0, 90.0, 0.0, 45.0, 0.0)]
_ANGLE = st.one_of(st.sampled_from([0.0, 90.0, -90.0, 180.0, 45.0]), st.floats(-180, 180))


@settings(max_examples=400, deadline=None)
@given(
    st.floats(-450, 450), st.floats(-450, 450), st.floats(-100, 600), _ANGLE, _ANGLE, _ANGLE,
    st.one_of(st.none(), st.sampled_from(POSES), st.tuples(*(st.floats(-180, 180) for _ in range(6)))),
)
def test_has_solution_is_exactly_whether_inverse_returns(x, y, z, b0, b1, w, near):
    near = HOME if near is None else near
    pose = (x, y, z, b0, b1, w)
    try:
        inverse(pose, LINKS, near, LIMITS)
        expected = True
    except Unreachable:
        expected = False
    assert has_solution(pose, LINKS, near, LIMITS) is expected


def test_has_solution_finds_both_answers():
    limits, links, home = LIMITS, LINKS, HOME
    assert has_solution((250, 0, 150, 180, 0, 0), links, home, limits)
    assert not has_solution((600, 0, 150, 180, 0, 0), links, home, limits)  # out of reach
    assert not has_solution(tuple(forward((0, 0, 0, 0, 90, 0), links)), links, home, [(-170, 170), (5, 100)] + list(limits[2:]))


# --- inverse's pruned search is the plain enumeration (issue 11: the simulator's IK per frame) ---


def _inverse_by_enumeration(pose, links, near, limits):
    """inverse as first written: fit every solution of ``solutions``, keep the nearest."""
    raw = solutions(pose, links, near)
    if not raw:
        return "out of the arm's reach"
    best, best_cost, worst = None, math.inf, None
    for solution in raw:
        fitted = []
        for k, angle in enumerate(solution):
            value = _fit(angle, near[k], None if limits is None else limits[k])
            if value is None:
                if worst is None:
                    worst = (k, angle)
                break
            fitted.append(value)
        else:
            cost = 0.0  # left to right, as first written (sum() of floats rounds otherwise from Python 3.12)
            for a, h in zip(fitted, near):
                cost += (a - h) ** 2
            if cost < best_cost:
                best, best_cost = tuple(fitted), cost
    return best if best is not None else f"J{worst[0] + 1} = {worst[1]:.1f}°"


@settings(max_examples=600, deadline=None)
@given(
    st.floats(-450, 450), st.floats(-450, 450), st.floats(-100, 600), _ANGLE, _ANGLE, _ANGLE,
    st.one_of(st.none(), st.sampled_from(POSES), st.tuples(*(st.floats(-180, 180) for _ in range(6)))),
    st.sampled_from([LIMITS, None, ((-30, 30),) * 6]),
    st.one_of(st.none(), st.tuples(*(st.floats(-60, 60) for _ in range(6)))),
)
def test_inverse_is_exactly_the_nearest_of_all_solutions(x, y, z, b0, b1, w, near, limits, from_joints):
    near = HOME if near is None else near
    # Poses the arm can take (FK of joints), as the simulator asks, and arbitrary ones.
    pose = tuple(forward(from_joints, LINKS)) if from_joints is not None else (x, y, z, b0, b1, w)
    expected = _inverse_by_enumeration(pose, LINKS, near, limits)
    try:
        found = inverse(pose, LINKS, near, limits)
    except Unreachable as error:
        assert isinstance(expected, str) and expected in str(error)
    else:
        assert found == expected  # bit for bit: the status frames must not change
