"""Found by the refused-target property (tests/test_refused_unseen.py, Hypothesis, 3,000 examples,
``--hypothesis-seed=1`` and ``3``): a target out of reach with a POSE behind it ended "finished",
exit 0, when the job's last target lies on the refused move's path.

The job: G1 X250, G1 X220 Z120, G1 X500 Z150 (out of reach: refused), POSE 1, G1 X225 Z121.
The last target, (225, 0, 121), lies on the refused move's path 5 mm past its start; the arm at
rest there gave two reports "on" that move past its start, which counted as the two that prove
it ran (``Ledger.prove_ran``).  An arm at rest shows no run, and a report that lies on a later
frame's path may be the arm there: the arm runs the frames after a refused move at once.
The simulator's record: frame 3 refused.
"""

from __future__ import annotations

import pytest

from test_found8_reports_on_an_earlier_frame_prove_no_run import assert_refused_line_3_named, check_refused_job


@pytest.mark.timeout(60)
def test_the_arm_at_rest_at_a_later_target_on_a_refused_path_does_not_prove_it_ran(tmp_path_factory):
    check_refused_job(tmp_path_factory, before=(220.0, 0.0, 120.0, 1500), far_mm=500, feed=3000,
                      following="pose", joints=(0.0, 0.0, 0.0), last=(225.0, 0.0, 121.0))


JOB = ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X220 Y0 Z120 F1500\nG1 X500 Y0 Z150 A180 B0 C0 F3000\n"
       "POSE 1\nG1 X225 Y0 Z121 A180 B0 C0 F3000\n")


@pytest.mark.timeout(60)
def test_the_same_job_through_the_installed_command_does_not_end_finished(tmp_path):
    assert_refused_line_3_named(tmp_path, JOB)
