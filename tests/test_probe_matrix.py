"""armctl probe on any arm the [connector] settings can describe: every combination of FIFO size
(50…250), control-frame mode, status X/Y/Z frame and speed factor (0.7…2.0) is recovered by one
probe with motion, in virtual time (issue 9's "Done when")."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from test_probe import ARM_TIME_LIMIT_S, assert_as_found, probe_sim, values


@pytest.mark.timeout(300)
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    fifo=st.integers(50, 250),
    control=st.sampled_from(["queued", "arrival"]),
    frame=st.sampled_from(["worktable", "robot"]),
    speed_factor=st.integers(70, 200).map(lambda hundredths: hundredths / 100),
)
def test_every_combination_of_the_settings_is_recovered(fifo, control, frame, speed_factor):
    probe, model, _ = probe_sim(f"fifo_frames={fifo}&control_frames={control}&status_xyz_frame={frame}"
                                f"&speed_factor={speed_factor}", motion=True)
    found = values(probe)
    assert (found["fifo_frames"], found["control_frames"], found["status_xyz_frame"]) == (fifo, control, frame)
    speed = probe.finding("speed_factor")
    assert speed.confidence == "sure" and abs(speed.value - speed_factor) <= speed.details["precision"]
    assert found["kinematics_verified"] is True  # the simulated arm's links are the profile's
    assert probe.arm_time_s <= ARM_TIME_LIMIT_S
    assert_as_found(model)
