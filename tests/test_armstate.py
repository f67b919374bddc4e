"""ArmState: the nine kinds merged, ages, completeness and H9's plausibility hold-back."""

from armctl.core.armstate import STALE_AFTER_S, ArmState
from armctl.core.protocol import (
    STATUS_ROTATION,
    FileLengthStatus,
    FileStatus,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PositionStatus,
    RunPositionStatus,
    WorktableStatus,
    WristStatus,
)

ONE_OF_EACH = [
    PositionStatus(100.5, -20, 30),
    JointsLowStatus(10, 20, 30),
    JointsHighStatus(-40, 50, 60.25),
    WorktableStatus(1, 2, 3),
    PauseStatus(1, 1500),
    WristStatus(5.5, -6.5),
    FileLengthStatus(1234.0),
    FileStatus(7),
    RunPositionStatus(600.0),
]


def test_complete_only_after_all_nine_kinds():
    state = ArmState()
    for k, frame in enumerate(ONE_OF_EACH):
        assert not state.complete
        assert state.update(frame, now=0.03 * k)
    assert state.complete
    assert state.to_json() == {
        "x": 100.5, "y": -20.0, "z": 30.0,
        "joints": [10.0, 20.0, 30.0, -40.0, 50.0, 60.25],
        "worktable": [1.0, 2.0, 3.0],
        "paused": True, "pwm": 1500, "w0": 5.5, "w1": -6.5,
        "file_length": 1234.0, "file_status": 7, "run_position": 600.0,
    }


def test_ages_and_stale_kinds():
    state = ArmState()
    state.update(PositionStatus(0, 0, 0), now=1.0)
    assert state.age(0, 1.5) == 0.5
    assert state.age(1, 1.5) is None
    assert 0 not in state.stale_kinds(1.0 + STALE_AFTER_S - 0.01)
    assert 0 in state.stale_kinds(1.0 + STALE_AFTER_S + 0.01)
    assert set(state.stale_kinds(1.0)) == set(STATUS_ROTATION) - {0}


def test_a_single_implausible_jump_is_held_back():
    state = ArmState(max_speed_mm_s=100.0)
    state.update(PositionStatus(0, 0, 0), now=0.0)
    # 0.27 s later the arm cannot be 500 mm away at 100 mm/s: one corrupted frame.
    assert not state.update(PositionStatus(500, 0, 0), now=0.27)
    assert state.position_mm == (0.0, 0.0, 0.0)
    assert state.suspect_frames == 1
    # The next frame agrees with the old position: the suspect one is forgotten.
    assert state.update(PositionStatus(10, 0, 0), now=0.54)
    assert state.position_mm == (10.0, 0.0, 0.0)


def test_a_real_jump_is_accepted_once_confirmed():
    state = ArmState(max_speed_mm_s=100.0)
    state.update(PositionStatus(0, 0, 0), now=0.0)
    assert not state.update(PositionStatus(500, 0, 0), now=0.27)
    assert state.update(PositionStatus(501, 0, 0), now=0.54)  # confirmed by its successor
    assert state.position_mm == (501.0, 0.0, 0.0)


def test_joint_jumps_are_judged_against_joint_speed():
    state = ArmState(max_joint_speed_deg_s=90.0)
    state.update(JointsLowStatus(0, 0, 0), now=0.0)
    assert state.update(JointsLowStatus(20, 0, 0), now=0.27)  # 24 deg + slack allowed
    assert not state.update(JointsLowStatus(200, 0, 0), now=0.54)


def test_without_limits_every_frame_is_accepted():
    state = ArmState()
    state.update(PositionStatus(0, 0, 0), now=0.0)
    assert state.update(PositionStatus(3000, 0, 0), now=0.01)
