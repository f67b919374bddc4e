"""Review 8: blips of the pause-and-PWM kind and of the position or joints, interleaved, on a 10 % noisy line.

scripts/joint_routine.txt on ``sim://?clock=virtual&noise=0.10&corrupt=0.10&seed=N``, seeds 1-20:
8 overran the simulator's record.  In three of them (3, 13, 19), and in part of a fourth (15),
no blip was missed: a pause-and-PWM blip and a position or joints blip overlapped, and each,
undone, put back the time of the last change it had saved when it left (``changed_s``) — which
held the other one's blip (seed 13: a pause byte of 227 at 17.70 s, a J6 of -186.88 at 17.91 s,
both back a rotation later: the job read 17.70 s, the arm at rest since 16.5 s).  Each kind
now puts back its own last change only (``readings_changed_s``, ``other_changed_s``).

The other five are what the rule does not take for a blip, and should not without an argument
that real motion cannot look so: seed 4, a position read three times in a row elsewhere (more
than ``BLIP_READINGS``); seed 11, joints 4-6 read twice elsewhere within a reading's jitter of
each other (2.29°, 2.23°: the arm settling, by the rule); seeds 15 (after this fix) and 12 of
pick_and_place, a corrupted reading within jitter (0.02°); seeds 16 and 18, two pause-and-PWM
readings in a row, each another value.

The patterns are fed to ``Readings`` directly too, the way tests/test_blips_noisy_line.py does.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from test_blips_noisy_line import JOINTS_HIGH, PAUSE, POSITION, _still_then
from test_review8_noise_end import _arm_times, _overran

pytestmark = pytest.mark.timeout(60)

JOINT_ROUTINE = Path(__file__).resolve().parents[1] / "scripts" / "joint_routine.txt"
def test_a_joints_blip_then_a_pause_blip_in_one_rotation_date_nothing():
    readings = _still_then([{JOINTS_HIGH: (0.0, 90.0, -186.88), PAUSE: (227, 1000)}])
    assert readings.changed_s == 0.03 * PAUSE, readings.changed_s


def test_a_pause_blip_then_a_position_blip_a_rotation_later_date_nothing():
    readings = _still_then([{PAUSE: (227, 1000)}, {POSITION: (210.0, 0.0, -2490.4)}])
    assert readings.changed_s == 0.03 * PAUSE, readings.changed_s


def test_joint_routine_at_ten_percent_where_blips_overlapped(monkeypatch):
    assert _overran(_arm_times(monkeypatch, JOINT_ROUTINE, (3, 13, 19), rate=0.10)) == {}
