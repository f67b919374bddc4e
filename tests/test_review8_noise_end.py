"""Review 8: a job that ends in POSE 0 on a noisy line (``noise=0.05&corrupt=0.05``) overstated the arm's time.

POSE 0 after Cartesian moves on the default profile (kinematics not verified) is a frame whose
path no model knows (``path_known`` False) and whose motion is the arm's own: until its time bound
runs out (some 20 s) it "explains" any reading (``Written.explains``), so a corrupted report after
the arm came to rest at the pose was counted as its motion, and the arm's time ran on to it.
scripts/pick_and_place.txt, seeds 1-20: 6 read more than the simulator's record allows (seed 3:
35.39 s for 31.24 s; seeds 2, 11, 12, 18, 20: 0.7-1.3 s over).  Once both joint halves have been
read at the pose's joints (two agreeing reports each) after the frame began, its motion is over
and it explains no later reading ("Blips" in armctl/core/job_readings.py).

The comparison is tests/test_blips_noisy_line.py's: the simulator's execution log is the truth.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(60)

ROOT = Path(__file__).resolve().parents[1]
PICK_AND_PLACE = ROOT / "scripts" / "pick_and_place.txt"
ROTATION_S = 0.27
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}
FAULT_2 = ("a corrupted report after the arm rested at POSE 0 counts as that frame's motion: pick_and_place's "
           "arm time overran the simulator's record on 6 of seeds 1-20 (seed 3: 35.39 s for 31.24 s)")


def _arm_times(monkeypatch, script: Path, seeds, rate: float = 0.05) -> dict:
    """seed -> (armctl's arm time, the simulator's record of it, outcome)."""
    from armctl import Arm
    from test_resume_exactly_once import _open_one_arm

    ports = _open_one_arm(monkeypatch)
    times = {}
    for seed in seeds:
        url = f"sim://?clock=virtual&noise={rate}&corrupt={rate}&seed={seed}"
        with Arm.open(url) as arm:
            result = arm.run(script)
        model = ports[url].model
        truth_s = model.execution_log[-1].end_s - (model.frames_received[0].arrival_s - 0.05)
        times[seed] = (result.arm_time_s, truth_s, result.outcome)
    return times


def _overran(times: dict) -> dict:
    return {seed: (round(arm_s, 3), round(truth_s, 3)) for seed, (arm_s, truth_s, outcome) in times.items()
            if outcome != "finished" or not truth_s - 0.01 <= arm_s <= truth_s + 2 * ROTATION_S + 0.1}


def test_pick_and_place_arm_time_on_a_noisy_line_is_the_arms(monkeypatch):
    """Seeds 1-20 but 12 (below)."""
    assert _overran(_arm_times(monkeypatch, PICK_AND_PLACE, [seed for seed in range(1, 21) if seed != 12])) == {}


@pytest.mark.xfail(strict=True, reason="seed 12: 31.965 s for 31.245 s — no POSE blip: joints 4-6 went unread at the "
                                       "arrival (a report lost), then a corrupted joints 1-3 report 0.15 deg off (within a "
                                       "reading's jitter, which 'Blips' lets date the motion: the arm settling) came back")
def test_pick_and_place_seed_12(monkeypatch):
    assert _overran(_arm_times(monkeypatch, PICK_AND_PLACE, [12])) == {}


@pytest.mark.parametrize("seed", [3, 18])
def test_the_installed_command_s_arm_time_is_the_clean_line_s(seed, tmp_path):
    """``armctl run --json`` in a fresh process: the noisy line's arm time within two rotations
    of the clean line's (the same arm, the same job: 31.25 s)."""
    def arm_time(url: str) -> float:
        out = subprocess.run([sys.executable, "-m", "armctl", "run", str(PICK_AND_PLACE), "--json", "-q", "--port", url],
                             cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=50)
        assert out.returncode == 0, out.stderr
        summary = json.loads(out.stdout.splitlines()[-1])
        assert summary["outcome"] == "finished", summary
        return summary["arm_time_s"]

    clean_s = arm_time("sim://?clock=virtual")
    assert clean_s - 0.01 <= arm_time(f"sim://?clock=virtual&noise=0.05&corrupt=0.05&seed={seed}") <= clean_s + 2 * ROTATION_S + 0.1


# --- Written.over on its own: what proves a fixed pose's motion over, and what does not ----------

from types import SimpleNamespace  # noqa: E402

from armctl.core.job_readings import ARRIVAL_SLACK_S, Written  # noqa: E402
from armctl.core.protocol import ArcEnd, GoToPose, LinearMove  # noqa: E402

POSE0 = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)  # the default profile's pose 0
HOME_XYZ = (210.0, 0.0, 300.0)  # where the arm reports it there


def _end(xyz=None, joints=None):
    return SimpleNamespace(xyz=xyz or (0.0, 0.0, 0.0), joints=joints or (0.0,) * 6, xyz_derived=xyz is None,
                           joints_derived=joints is None, pwm_us=(), origin_mm=(0.0, 0.0, 0.0))


def _frame(index, command, kind, start, end, path_known=True, wire_end_s=0.0, certain_end_s=99.0):
    segment = SimpleNamespace(kind=kind, start=start, end=end, moves_reported=True)
    return SimpleNamespace(index=index, command=command, segment=segment, path_known=path_known, wire_end_s=wire_end_s,
                           certain_end_s=certain_end_s, tag=None)


def _written(before_kind: str = "line"):
    """Frame 0 lifts the tool from (250, 120, 60) to (250, 120, 150) (a line; or an arc through
    there), frame 1 is POSE 0 (its path unknown), both landed by t = 1 s; nothing known finished."""
    written = Written()
    command = LinearMove(250, 120, 150, 180, 0, 0, 1000, 1500) if before_kind == "line" else ArcEnd(250, 120, 150, 180, 0, 0, 1000, 1500)
    written.note(_frame(0, command, before_kind, _end(xyz=(250.0, 120.0, 60.0)), _end(xyz=(250.0, 120.0, 150.0))))
    written.note(_frame(1, GoToPose(0), "joint", _end(xyz=(250.0, 120.0, 150.0)), _end(joints=POSE0), path_known=False,
                        wire_end_s=0.5))
    return written


def _read_at_pose(written, position, first_s=2.0):
    """Two agreeing reports of each kind: the position at ``position``, the joints at pose 0."""
    written.over({0: (position, first_s, first_s + 0.27), 1: (POSE0[:3], first_s + 0.03, first_s + 0.3),
                  2: (POSE0[3:], first_s + 0.06, first_s + 0.33)})


def test_the_pose_read_at_its_end_off_the_path_of_every_frame_before_it_is_over():
    written = _written()
    assert written.explains(0, (491.6, 0.0, 300.0), 3.0)  # before: any reading, until its time bound
    _read_at_pose(written, HOME_XYZ)
    assert written.over_s == {1: 2.06}
    assert not written.explains(0, (491.6, 0.0, 300.0), 3.0)  # a corrupted report after that: no motion of it
    assert written.explains(0, (491.6, 0.0, 300.0), 2.0)  # (read before it was proven over: as before)


def test_a_reading_on_the_path_of_a_frame_before_it_proves_nothing():
    """The lift may still run where the arm reads (250, 120, 100): POSE 0 may not have begun."""
    written = _written()
    _read_at_pose(written, (250.0, 120.0, 100.0))
    assert written.over_s == {}
    assert written.explains(0, (491.6, 0.0, 300.0), 3.0)


def test_an_arc_before_it_proves_nothing():
    """An arc's path leaves the span of its ends: a reading off that span may be on the arc."""
    written = _written("arc")
    _read_at_pose(written, HOME_XYZ)
    assert written.over_s == {}


def test_a_reading_before_the_pose_landed_proves_nothing():
    written = _written()
    _read_at_pose(written, HOME_XYZ, first_s=0.5 + ARRIVAL_SLACK_S - 0.1)
    assert written.over_s == {}


def test_joints_elsewhere_than_the_pose_prove_nothing():
    written = _written()
    written.over({0: (HOME_XYZ, 2.0, 2.27), 1: ((0.0, 0.5, 0.0), 2.03, 2.3), 2: (POSE0[3:], 2.06, 2.33)})
    assert written.over_s == {}


def test_every_frame_before_it_known_finished_proves_it_began():
    written = _written()
    written.done(1, 1.5)  # the lift known finished (by a report read at 1.5 s)
    _read_at_pose(written, (250.0, 120.0, 100.0))  # (the position then proves nothing more)
    assert written.over_s == {1: 2.06}
