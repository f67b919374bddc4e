"""A corrupted report is not the arm working: the summary's arm time and its "kept working" note
claim only what the arm's reports show.

Found by the probe review: status frames have no checksum (PROTOCOL.md H9), so a corrupted one
reads as the arm somewhere else.  Read after the arm stopped, with the next report of its kind
back at the old value and nothing else changed in between, it counted as motion: the arm time
ran to the last such report (scripts/joint_routine.txt on
``sim://?clock=virtual&loss=0.05&corrupt=0.02&noise=0.02``: 24.0, 25.0, 21.1 and 30.7 s on seeds
2, 7, 11 and 12, for an arm that the simulator's record shows at rest by 16.5 s) and the summary
added "the arm kept working past the estimate".  A reading alone between two equal ones of its
kind, with no other kind changed meanwhile, is a blip (``job_readings``): it does not date the
arm's motion.
"""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from armctl.core.protocol import JointsHighStatus
from armctl.ui.cli import main
from test_probe_review import JOINT_ROUTINE, NOISY
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)

ROTATION_S = 0.27  # nine kinds, 30 ms apart: a reading of each kind comes at most this late


@pytest.mark.parametrize("seed", [1, 2, 7, 11, 12, 17, 18, 28, 38])
def test_the_arm_time_is_the_arms_not_a_corrupted_reports(tmp_path, monkeypatch, seed):
    monkeypatch.chdir(tmp_path)
    url = NOISY.format(seed=seed)
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", str(JOINT_ROUTINE), "--json", "--port", url], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    executions = ports[url].model.execution_log
    arm_s = executions[-1].end_s - executions[0].start_s  # the simulator's own record of the arm
    assert summary["outcome"] == "finished", result.output
    # the reports come a rotation apart: the arm is seen at rest at most a rotation or two after it
    assert arm_s - 0.1 <= summary["arm_time_s"] <= arm_s + 2 * ROTATION_S + 0.1, (arm_s, summary)
    assert not any("kept working" in m for m in summary["messages"]), summary["messages"]


def test_a_reading_that_settles_is_no_blip():
    """The wrist read at 2.00 then 2.01 degrees (the arm settling, within a reading's jitter) then
    back at 0: the reading at 2 was not alone, so its return ends no blip — the motion dates from
    the return.  (A change within jitter kept the candidate of its own kind, as it rightly does one
    of another kind, and the return undid the motion.)"""
    from armctl.core.job_readings import Readings, Written

    readings = Readings(Written())
    wrist = JointsHighStatus.KIND
    for t, j6 in ((0.0, 0.0), (0.27, 0.0), (0.54, 2.0), (0.81, 2.01), (1.08, 0.0)):
        for kind, values in ((0, (250.0, 0.0, 150.0)), (1, (0.0, 0.0, 0.0)), (wrist, (0.0, 90.0, j6)), (4, (0, 1500))):
            readings.take(kind, values, t + 0.03 * kind)
    assert readings.motion[1] == 1.08 + 0.03 * wrist, readings.motion
