"""The motion-time model: every duration below is worked out by hand from the rules in motion.py."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.core.motion import (
    TINY_MM,
    ArmPose, MotionModel, Planner, arc_through, circle_through, distance_to_path, on_path,
)
from armctl.host.profile import parse_profile
from armctl.core.protocol import (
    AccelLinearMove, ArcEnd, ArcStart, Delay, GoToPose, JointMove, LinearMove, MCode, PauseToggle, ResetArm,
    SetWorktableOrigin,
)

PROFILE = parse_profile({
    "speed": {"max_linear_mm_min": 12000, "max_joint_deg_s": 90, "max_accel_mm_s2": 3200, "attitude_deg_s": 90},
    "timing": {"joint_ramp_s": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], "command_overhead_s": 0.0, "pwm_change_s": 0.25,
               "pose_smoothing": 2},
    "links": {"base_height_mm": 150, "shoulder_offset_mm": 30, "upper_arm_mm": 180, "elbow_offset_mm": 30,
              "forearm_mm": 180, "tool_mm": 60},
    "poses": {"1": [0, 30, 30, 0, 30, 0]},
})
MODEL = MotionModel(PROFILE)
DOWN = (180.0, 0.0, 0.0)  # tool straight down


def at(x, y, z, attitude=DOWN, pwm=1500.0, model=MODEL):
    return ArmPose(model.kinematics, cartesian=(x, y, z, *attitude), pwm_us=(pwm,) * 4)


START = at(200, 0, 200)


def line(x, y, z, speed=6000.0, attitude=DOWN, pwm=1500.0, **kw):
    return LinearMove(x, y, z, *attitude, pwm_us=pwm, speed_mm_min=speed, **kw)


def accel(mode, x, y, z, a, speed1, speed0=0.0):
    return AccelLinearMove(mode, x, y, z, *DOWN, accel_mm_s2=a, speed1_mm_min=speed1, speed0_mm_min=speed0)


def along_x(segment, t):
    return segment.sample(t).cartesian.x_mm - 200


# --- linear move ----------------------------------------------------------------------------


def test_linear_move_100_mm_at_6000_mm_min_takes_one_second():
    segment = MODEL.plan(line(300, 0, 200), START)
    assert segment.kind == "line" and segment.space == "cartesian"
    assert segment.duration_s == pytest.approx(1.0)
    assert segment.length == pytest.approx(100.0)
    assert along_x(segment, 0.25) == pytest.approx(25.0)
    assert segment.note is None


def test_sample_clamps_and_ends_exactly_at_end():
    segment = MODEL.plan(line(300, 0, 200), START)
    assert segment.sample(-1.0) is segment.start and segment.sample(0.0) is segment.start
    assert segment.sample(segment.duration_s) is segment.end and segment.sample(99.0) is segment.end
    assert segment.sample(segment.duration_s - 1e-9).isclose(segment.end, mm=1e-6, deg=1e-5)
    assert segment.end.cartesian == (300, 0, 200, *DOWN)


def test_sampled_joints_come_from_ik_and_match_fk():
    segment = MODEL.plan(line(300, 50, 150), START)
    pose = segment.sample(0.3)
    x, y, z = MODEL.kinematics.forward(pose.joints)[:3]
    assert (x, y, z) == pytest.approx(pose.xyz, abs=1e-6)


def test_speed_above_the_profile_maximum_is_clamped_and_noted():
    segment = MODEL.plan(line(300, 0, 200, speed=24000), START)
    assert segment.duration_s == pytest.approx(0.5)  # 100 mm at 12000 mm/min
    assert "clamped" in segment.note


def test_attitude_only_move_is_timed_by_the_attitude_rate():
    segment = MODEL.plan(line(200, 0, 200, attitude=(180, 0, 45)), START)
    assert segment.length == 0 and segment.duration_s == pytest.approx(0.5)  # 45° at 90°/s
    assert segment.sample(0.25).cartesian.w_deg == pytest.approx(22.5)


def test_attitude_goes_the_short_way_round():
    start = at(200, 0, 200, attitude=(180, 0, 170))
    segment = MODEL.plan(line(200, 0, 200, attitude=(180, 0, -170)), start)
    assert segment.duration_s == pytest.approx(20 / 90)


def test_attitude_slower_than_the_move_stretches_it():
    segment = MODEL.plan(line(210, 0, 200, attitude=(180, 0, 90)), START)  # 10 mm = 0.1 s, 90° = 1 s
    assert segment.duration_s == pytest.approx(1.0)
    assert along_x(segment, 0.5) == pytest.approx(5.0)


def test_external_axes_are_timed_at_the_joint_speed():
    segment = MODEL.plan(line(200, 0, 200, e0_deg=45), START)
    assert segment.duration_s == pytest.approx(0.5) and segment.sample(0.25).e0_deg == pytest.approx(22.5)


def test_pwm_only_move_waits_for_the_servo():
    segment = MODEL.plan(line(200, 0, 200, pwm=2000), START)
    assert segment.duration_s == pytest.approx(0.25)
    assert segment.sample(0.1).pwm_us[0] == 2000 and segment.sample(0.0).pwm_us[0] == 1500


def test_pwm_channel_selects_the_slot():
    segment = MODEL.plan(line(200, 0, 200, pwm=900, pwm_channel=3), START)
    assert segment.end.pwm_us == (1500, 1500, 900, 1500)


def test_repeated_target_takes_no_time():
    assert MODEL.plan(line(200, 0, 200), START).duration_s == 0.0


# --- accelerated linear move ------------------------------------------------------------------
# speed1 6000 mm/min = 100 mm/s; a = 500 mm/s² reaches it in 0.2 s over 10 mm.


def test_mode0_accelerates_then_cruises():
    segment = MODEL.plan(accel(0, 300, 0, 200, 500, 6000), START)
    assert segment.duration_s == pytest.approx(0.2 + 0.9)
    assert along_x(segment, 0.1) == pytest.approx(0.5 * 500 * 0.1**2)
    assert along_x(segment, 0.2) == pytest.approx(10.0)
    assert along_x(segment, 0.7) == pytest.approx(60.0)


def test_mode0_short_never_reaches_speed1():
    segment = MODEL.plan(accel(0, 204, 0, 200, 500, 6000), START)
    assert segment.duration_s == pytest.approx(math.sqrt(2 * 4 / 500))


def test_mode0_negative_cruises_then_decelerates_to_zero():
    segment = MODEL.plan(accel(0, 300, 0, 200, -500, 6000), START)
    assert segment.duration_s == pytest.approx(0.9 + 0.2)
    assert along_x(segment, 0.5) == pytest.approx(50.0)
    assert along_x(segment, 1.0) == pytest.approx(90 + 100 * 0.1 - 0.5 * 500 * 0.1**2)


def test_mode0_negative_short_starts_slower():
    segment = MODEL.plan(accel(0, 204, 0, 200, -500, 6000), START)
    assert segment.duration_s == pytest.approx(math.sqrt(2 * 4 / 500))


def test_mode1_trapezoid():
    segment = MODEL.plan(accel(1, 300, 0, 200, 1000, 6000), START)  # ramps 0.1 s / 5 mm each
    assert segment.duration_s == pytest.approx(0.1 + 0.9 + 0.1)
    assert along_x(segment, 0.05) == pytest.approx(0.5 * 1000 * 0.05**2)
    assert along_x(segment, 1.05) == pytest.approx(100 - 0.5 * 1000 * 0.05**2)


def test_mode1_triangle_when_too_short():
    segment = MODEL.plan(accel(1, 204, 0, 200, 1000, 6000), START)
    half = math.sqrt(2 * 2 / 1000)  # 2 mm up, 2 mm down
    assert segment.duration_s == pytest.approx(2 * half)
    assert along_x(segment, half) == pytest.approx(2.0)


def test_mode2_from_speed0_to_speed1():
    segment = MODEL.plan(accel(2, 300, 0, 200, 500, 6000, speed0=3000), START)
    ramp = (100**2 - 50**2) / (2 * 500)  # 7.5 mm in 0.1 s
    assert segment.duration_s == pytest.approx(0.1 + (100 - ramp) / 100)
    assert along_x(segment, 0.1) == pytest.approx(ramp)


def test_mode2_decelerates_when_speed0_is_higher():
    segment = MODEL.plan(accel(2, 300, 0, 200, 500, 3000, speed0=6000), START)
    assert segment.duration_s == pytest.approx(0.1 + (100 - 7.5) / 50)


def test_zero_acceleration_is_constant_speed1_and_noted():
    segment = MODEL.plan(accel(1, 300, 0, 200, 0, 6000), START)
    assert segment.duration_s == pytest.approx(1.0) and "acceleration 0" in segment.note


# --- joint move -----------------------------------------------------------------------------

HOME = MODEL.initial_pose((0, 0, 0, 0, 90, 0))


def joint(*joints, speed=45.0, smoothing=0, pwm=1500.0):
    return JointMove(*joints, pwm_us=pwm, speed_deg_s=speed, smoothing=smoothing)


def test_joint_move_lead_joint_over_speed():
    segment = MODEL.plan(joint(90, 0, 0, 0, 90, 0), HOME)
    assert segment.kind == "joint" and segment.duration_s == pytest.approx(2.0)
    assert segment.sample(1.0).joints[0] == pytest.approx(45.0)


def test_joint_moves_are_synchronous():
    segment = MODEL.plan(joint(90, 30, 0, 0, 90, 0), HOME)
    pose = segment.sample(0.5)
    assert pose.joints[1] / pose.joints[0] == pytest.approx(30 / 90)


def test_joint_smoothing_adds_its_ramp():
    segment = MODEL.plan(joint(90, 0, 0, 0, 90, 0, smoothing=2), HOME)  # ramp 0.2 s: 45/0.2 = 225 deg/s²
    assert segment.duration_s == pytest.approx(2.0 + 0.2)
    assert segment.sample(0.1).joints[0] == pytest.approx(0.5 * 225 * 0.1**2)
    assert segment.sample(1.1).joints[0] == pytest.approx(45.0)


def test_short_smoothed_joint_move_is_a_triangle():
    segment = MODEL.plan(joint(2, 0, 0, 0, 90, 0, smoothing=2), HOME)  # ramping alone needs 9°
    assert segment.duration_s == pytest.approx(2 * math.sqrt(2 * 1 / 225))  # 1° up, 1° down


def test_joint_move_cartesian_is_fk():
    segment = MODEL.plan(joint(30, 10, 10, 0, 70, 0), HOME)
    pose = segment.sample(0.3)
    assert pose.cartesian == pytest.approx(MODEL.kinematics.forward(pose.joints))


def test_joint_speed_is_clamped():
    segment = MODEL.plan(joint(90, 0, 0, 0, 90, 0, speed=180), HOME)
    assert segment.duration_s == pytest.approx(1.0) and "clamped" in segment.note


def test_joint_move_needs_start_joints_of_a_cartesian_pose():
    segment = MODEL.plan(joint(0, 0, 0, 0, 90, 0), at(210, 0, 300))  # home, given in Cartesian terms
    assert segment.duration_s == pytest.approx(0.0, abs=1e-6)


# --- arcs -----------------------------------------------------------------------------------


def test_circle_through_known_points():
    center, radius, normal = circle_through((10, 0, 5), (0, 10, 5), (-10, 0, 5))
    assert center == pytest.approx((0, 0, 5)) and radius == pytest.approx(10) and normal == pytest.approx((0, 0, 1))
    arc = arc_through((10, 0, 5), (0, -10, 5), (-10, 0, 5))
    assert arc.normal == pytest.approx((0, 0, -1)) and arc.sweep_rad == pytest.approx(math.pi)
    assert arc_through((10, 0, 0), (0, 10, 0), (0, -10, 0)).sweep_rad == pytest.approx(1.5 * math.pi)


def test_circle_through_degenerate_points():
    assert circle_through((0, 0, 0), (1, 1, 1), (2, 2, 2)) is None
    assert circle_through((0, 0, 0), (0, 0, 0), (2, 0, 0)) is None
    assert circle_through((0, 0, 0), (1, 0.01, 0), (2, 0, 0), tol_mm=0.1) is None


def half_circle(speed_start=3000.0, speed_end=3000.0):
    # From (200, 0, 200) through (250, 50, 200) to (300, 0, 200): radius 50, length 50π.
    return [ArcStart(250, 50, 200, *DOWN, pwm_us=1500, radius_mm=50, speed_mm_min=speed_start),
            ArcEnd(300, 0, 200, *DOWN, pwm_us=1500, speed_mm_min=speed_end)]


def test_arc_start_takes_no_time_and_the_half_circle_has_its_length():
    planner = Planner(MODEL, START)
    first, second = planner.feed_all(half_circle())
    assert first.duration_s == 0 and first.kind == "still"
    assert second.kind == "arc" and second.length == pytest.approx(50 * math.pi)
    assert second.duration_s == pytest.approx(50 * math.pi / 50)  # 3000 mm/min = 50 mm/s
    assert second.sample(second.duration_s / 2).xyz == pytest.approx((250, 50, 200))
    assert second.note is None
    assert planner.pose is second.end and planner.pending_arc is None


def test_arc_speed_changes_linearly_in_time():
    arc_start, arc_end = half_circle(3000, 6000)  # 50 → 100 mm/s
    segment = MODEL.plan(arc_end, START, arc_start=arc_start)
    length = 50 * math.pi
    assert segment.duration_s == pytest.approx(2 * length / (50 + 100))
    accel = (100**2 - 50**2) / (2 * length)
    t = 0.7
    assert segment.fraction_at(t) == pytest.approx((50 * t + 0.5 * accel * t * t) / length)


def test_collinear_arc_falls_back_to_a_line():
    arc_start = ArcStart(250, 0, 200, *DOWN, pwm_us=1500, radius_mm=50, speed_mm_min=6000)
    segment = MODEL.plan(ArcEnd(300, 0, 200, *DOWN, pwm_us=1500, speed_mm_min=6000), START, arc_start=arc_start)
    assert segment.kind == "line" and "collinear" in segment.note and segment.duration_s == pytest.approx(1.0)


def test_arc_end_without_arc_start_is_a_noted_line():
    segment = Planner(MODEL, START).feed(ArcEnd(300, 0, 200, *DOWN, pwm_us=1500, speed_mm_min=6000))
    assert segment.kind == "line" and "without its arc start" in segment.note


def test_arc_radius_mismatch_is_noted():
    arc_start = ArcStart(250, 50, 200, *DOWN, pwm_us=1500, radius_mm=80, speed_mm_min=3000)
    segment = MODEL.plan(half_circle()[1], START, arc_start=arc_start)
    assert segment.kind == "arc" and "radius" in segment.note


# --- the rest -------------------------------------------------------------------------------


def test_delay_mcode_and_control_frames():
    assert MODEL.plan(Delay(500), START).duration_s == pytest.approx(0.5)
    for command in (MCode(3), PauseToggle(), ResetArm(), ArcStart(1, 2, 3, 0, 0, 0, 1500, 5, 100)):
        segment = MODEL.plan(command, START)
        assert segment.duration_s == 0 and segment.end is START and segment.kind == "still"


def test_go_to_pose_is_a_joint_move_at_the_profile_speed():
    segment = MODEL.plan(GoToPose(1), HOME)  # lead joint J5: 90 → 30 at 90°/s, smoothing 2 (0.2 s)
    assert segment.kind == "joint" and segment.end.joints == PROFILE.poses[1]
    assert segment.duration_s == pytest.approx(60 / 90 + 0.2)


def test_worktable_origin_shifts_coordinates_not_the_arm():
    segment = MODEL.plan(SetWorktableOrigin(100, 0, 50), START)
    assert segment.duration_s == 0
    assert segment.end.xyz == pytest.approx((100, 0, 150))
    assert segment.end.robot_cartesian == pytest.approx(START.robot_cartesian)
    assert segment.end.joints == pytest.approx(START.joints)
    moved = MODEL.plan(line(150, 0, 150), segment.end)  # worktable (150, 0, 150) = robot (250, 0, 200)
    assert moved.duration_s == pytest.approx(0.5)
    assert moved.end.robot_cartesian[:3] == pytest.approx((250, 0, 200))


def test_speed_factor_scales_motion_not_delays():
    slow = MotionModel(PROFILE, speed_factor=1.3)
    segment = slow.plan(line(300, 0, 200), START)
    assert segment.duration_s == pytest.approx(1.3)
    assert segment.sample(0.65).xyz == pytest.approx(MODEL.plan(line(300, 0, 200), START).sample(0.5).xyz)
    assert slow.plan(joint(90, 0, 0, 0, 90, 0), HOME).duration_s == pytest.approx(2.6)
    assert slow.plan(Delay(500), START).duration_s == pytest.approx(0.5)
    with pytest.raises(ValueError):
        MotionModel(PROFILE, speed_factor=0)


def test_command_overhead_waits_at_the_start():
    model = MotionModel(parse_profile({"timing": {"command_overhead_s": 0.1},
                                       "speed": {"max_linear_mm_min": 12000}}))
    segment = model.plan(line(300, 0, 200), at(200, 0, 200, model=model))
    assert segment.duration_s == pytest.approx(1.1)
    assert segment.sample(0.05).xyz == pytest.approx((200, 0, 200))
    assert along_x(segment, 0.6) == pytest.approx(50.0)
    assert model.plan(MCode(1), segment.end).duration_s == pytest.approx(0.1)
    assert model.plan(ArcStart(1, 2, 3, 0, 0, 0, 1500, 5, 100), segment.end).duration_s == 0


def test_time_at_fraction_inverts_fraction_at():
    segment = MODEL.plan(accel(1, 300, 0, 200, 1000, 6000), START)
    for t in (0.0, 0.03, 0.1, 0.5, 1.05, 1.1):
        assert segment.time_at_fraction(segment.fraction_at(t)) == pytest.approx(t, abs=1e-9)


def test_unreachable_samples_keep_the_last_known_joints():
    segment = MODEL.plan(line(900, 0, 200), START)
    assert segment.end.joints == pytest.approx(START.joints)


# --- on the path? ---------------------------------------------------------------------------


def quantised(xyz):
    return tuple(round(v * 10) / 10 for v in xyz)  # status frames report 0.1 mm


def test_distance_to_a_line():
    segment = MODEL.plan(line(300, 0, 200), START)
    assert distance_to_path(segment, (250, 0, 200)) == pytest.approx((0, 0.5))
    assert distance_to_path(segment, (250, 3, 196)) == pytest.approx((5, 0.5))
    assert distance_to_path(segment, (350, 0, 200)) == pytest.approx((50, 1.0))
    assert on_path(segment, quantised(segment.sample(0.333).xyz)) == pytest.approx(0.333, abs=1e-3)
    assert on_path(segment, (250, 1, 200)) is None


def test_observed_joints_on_a_cartesian_path_go_through_fk():
    segment = MODEL.plan(line(300, 0, 200), START)
    joints = tuple(round(j, 2) for j in segment.sample(0.25).joints)  # status frames report 0.01°
    distance, fraction = distance_to_path(segment, joints)
    assert distance < 0.2 and fraction == pytest.approx(0.25, abs=1e-3)


def test_distance_to_an_arc():
    arc_start, arc_end = half_circle()
    segment = MODEL.plan(arc_end, START, arc_start=arc_start)
    assert distance_to_path(segment, (250, 50, 200)) == pytest.approx((0, 0.5), abs=1e-9)
    assert distance_to_path(segment, (250, 46, 203)) == pytest.approx((5, 0.5), abs=1e-9)
    assert distance_to_path(segment, (250, -50, 200))[1] in (0.0, 1.0)  # the other half: nearest end
    assert on_path(segment, quantised(segment.sample(1.0).xyz)) == pytest.approx(1 / math.pi, abs=1e-3)


def test_distance_to_a_joint_path_in_degrees_and_in_mm():
    segment = MODEL.plan(joint(90, 0, 0, 0, 90, 0), HOME)
    assert distance_to_path(segment, (45, 0, 0, 0, 90, 0)) == pytest.approx((0, 0.5))
    assert distance_to_path(segment, (45, 0.3, 0, 0, 90, 0)) == pytest.approx((0.3, 0.5))
    assert on_path(segment, (45, 0.03, 0, 0, 90, 0)) == pytest.approx(0.5)
    distance, fraction = distance_to_path(segment, segment.sample(0.5).xyz)  # FK trace, 16 chords
    assert distance < 1.0 and fraction == pytest.approx(0.25, abs=0.02)


def test_still_segments_prove_no_progress():
    segment = MODEL.plan(Delay(100), START)
    assert distance_to_path(segment, (200, 0, 201)) == pytest.approx((1, 0))
    with pytest.raises(ValueError):
        distance_to_path(segment, (1, 2))


# --- properties -----------------------------------------------------------------------------

targets = st.tuples(st.floats(150, 300), st.floats(-100, 100), st.floats(50, 250))


@settings(max_examples=150, deadline=None)
@given(targets, st.integers(0, 2), st.floats(-3200, 3200), st.floats(100, 12000), st.floats(0, 12000))
def test_accelerated_moves_progress_monotonically_and_end_at_end(target, mode, a, speed1, speed0):
    if mode != 2:
        speed0 = 0.0
    segment = MODEL.plan(accel(mode, *target, a, speed1, speed0), START)
    assert 0 <= segment.duration_s < math.inf
    if segment.duration_s == 0:  # the target is the start: nothing to do, done at once
        assert segment.length == 0 and segment.fraction_at(0) == 1.0
        return
    fractions = [segment.fraction_at(segment.duration_s * k / 20) for k in range(20)]
    fractions.append(segment.fraction_at(segment.duration_s))
    assert all(b >= a - 1e-12 for a, b in zip(fractions, fractions[1:]))
    assert fractions[-1] == 1.0 and fractions[0] == 0.0
    assert segment.sample(segment.duration_s) is segment.end
    assert segment.sample(segment.duration_s * (1 - 1e-9)).xyz == pytest.approx(segment.end.xyz, abs=1e-3)


@settings(max_examples=100, deadline=None)
@given(st.lists(targets, min_size=1, max_size=8), st.floats(0.5, 1.5))
def test_planner_chains_segments_end_to_start(points, factor):
    model = MotionModel(PROFILE, speed_factor=factor)
    planner = Planner(model, START)
    previous = START
    for point in points:
        segment = planner.feed(line(*point))
        assert segment.start is previous
        # Moves shorter than TINY_MM count as no motion (duration 0), hence the absolute tolerance.
        expected = math.dist(previous.xyz, segment.end.xyz) / 100 * factor
        assert segment.duration_s == pytest.approx(expected, abs=TINY_MM / 100 * factor)
        previous = segment.end


def _composed_line_distance(segment, p):
    """LineSegment._distance_xyz as it was composed of the vector helpers (before it was
    written out for the streamer's every position report): the reference it must equal."""
    from armctl.core.motion_paths import dot3, norm3, sub3

    if not segment.length:
        return norm3(sub3(p, segment._p0)), 0.0
    u = min(max(dot3(sub3(p, segment._p0), segment._d) / (segment.length * segment.length), 0.0), 1.0)
    return norm3(sub3(p, segment._point(u))), u


_ANY_FLOAT = st.one_of(st.floats(-1e3, 1e3), st.sampled_from([0.0, -0.0, 1e-300, 1e300, math.inf, -math.inf, math.nan]))


@settings(max_examples=400, deadline=None)
@given(st.tuples(_ANY_FLOAT, _ANY_FLOAT, _ANY_FLOAT), st.tuples(_ANY_FLOAT, _ANY_FLOAT, _ANY_FLOAT),
       st.one_of(st.floats(1e-3, 400.0), st.sampled_from([100.0, 1e-200])), st.tuples(_ANY_FLOAT, _ANY_FLOAT, _ANY_FLOAT))
def test_a_line_distance_is_the_vector_helpers_float_for_float(p0, d, length, p):
    from armctl.core.motion import LineSegment

    segment = LineSegment.__new__(LineSegment)  # only the fields _distance_xyz reads
    segment._p0, segment._d, segment.length = p0, d, length

    def outcome(distance_xyz):
        try:
            return [(v, math.copysign(1.0, v), v != v) for v in distance_xyz(segment, p)]
        except ZeroDivisionError:  # a length whose square underflows: both divide by zero
            return "ZeroDivisionError"

    expected, got = outcome(_composed_line_distance), outcome(LineSegment._distance_xyz)
    if isinstance(expected, str) or isinstance(got, str):
        assert got == expected
    else:  # the same float (NaN as NaN), sign of zero included
        assert all(a[1:] == b[1:] and (a[2] or a[0] == b[0]) for a, b in zip(got, expected))


_SLOTS = ("kinematics", "_cartesian", "_joints", "_hint", "pwm_us", "e0_deg", "e1_deg", "origin_mm", "xyz_derived",
          "joints_derived")


@settings(max_examples=200, deadline=None)
@given(st.lists(_ANY_FLOAT, min_size=6, max_size=6), st.lists(st.floats(500, 2500), min_size=4, max_size=4),
       _ANY_FLOAT, _ANY_FLOAT, st.lists(_ANY_FLOAT, min_size=3, max_size=3), st.lists(_ANY_FLOAT, min_size=6, max_size=6))
def test_at_cartesian_builds_the_pose_the_keyword_constructor_builds(cartesian, pwm, e0, e1, origin, hint):
    """The planner's fast constructor of a Cartesian end: every slot the same object or equal bits."""
    args = (tuple(cartesian), tuple(pwm), e0, e1, tuple(origin), tuple(hint))
    fast = ArmPose.at_cartesian(MODEL.kinematics, *args)
    slow = ArmPose(MODEL.kinematics, cartesian=args[0], pwm_us=args[1], e0_deg=e0, e1_deg=e1, origin_mm=args[4],
                   hint=args[5])
    for name in _SLOTS:
        a, b = getattr(fast, name), getattr(slow, name)
        assert type(a) is type(b) and repr(a) == repr(b), name  # repr: -0.0 and nan told apart, unlike ==
