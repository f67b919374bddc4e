"""Found by the connector-settings property (tests/test_connector_settings.py, Hypothesis): on an
arm with an 8-frame FIFO, a job held by the FIFO bound waited for ever with the arm at rest.

The job: … a move to (180, 80, 90), M9, a PWM-only move there, POSE 2, M108, M164, a delay, a
joint move.  Nine frames written, the lower bound at frame 5 (M9), four in flight: the FIFO bound
holds frame 9 until the lower bound passes frame 5.  The arm ran all nine and rests at pose 2.
The rest proves nothing past frame 5 (``JobEnd.resting_before_last_move``): an arm resting in M9
or the PWM-only move, at (180, 80, 90), might read as at the last target — compared in joints,
and that pose's joints are the profile's unverified kinematics'.  But the arm's X/Y/Z readings
say (0, 210, 300): it is not at (180, 80, 90), which needs no kinematics to see, so it is not
resting in those frames.  No time bound ran out for them either (the engine waited with no
deadline): the job stood still until the property's time limit, 3,600 s of the arm's time.
"""

from __future__ import annotations

import pytest

from test_connector_settings import check_random_job

OPS = [("joint", 4, 30.0, 3), ("arc", 4, 0), ("accel", 4, 0), ("accel", 3, 2), ("mcode", 9), ("pwm", 2000.0),
       ("pose", 2), ("pwm", 2000.0), ("mcode", 108), ("mcode", 164), ("delay", 50.0), ("joint", 4, 30.0, 3)]


@pytest.mark.timeout(60)
@pytest.mark.parametrize("speed_factor", (0.7, 1.0))
def test_a_held_job_goes_on_when_the_arm_rests_away_from_the_frames_that_move_nothing(speed_factor):
    check_random_job(OPS, 8, "queued", "worktable", speed_factor, 1.0, None, 0.0, 1, 2.0, time_limit_s=600.0)
