"""Found by the refused-target property (tests/test_refused_unseen.py, Hypothesis, 3,000 examples,
``--hypothesis-seed=1``): a target out of reach with a joint move behind it ended "finished", exit 0.

The job: G1 X250, then G1 X220 (back along Y0 Z150), G1 X500 (out of reach: refused), a G6, a G1.
The refused move's refusal only reports on its path can prove or disprove (a G6 behind it:
``Ledger.prove_ran``), and two reports counted as the arm on it — X 244.7 and 231.2 at Y0 Z150,
taken while the arm ran the line *before* it, X250 → X220, which runs back over the first 30 mm
of the X220 → X500 path.  A report that lies on an earlier pending frame's path may be the arm
there: it proves nothing about a later frame.  The simulator's record: frame 3 refused.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from test_refused_unseen import test_a_refused_target_never_ends_finished_whatever_joint_move_or_pose_follows as prop

check_refused_job = prop.hypothesis.inner_test


@pytest.mark.timeout(60)
def test_reports_on_the_line_before_a_refused_move_do_not_prove_it_ran(tmp_path_factory):
    check_refused_job(tmp_path_factory, before=(220.0, 0.0, 150.0, 3000), far_mm=500, feed=1500,
                      following="joint-move", joints=(0.0, 0.0, 0.0), last=(200.0, 0.0, 100.0))


JOB = ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X220 Y0 Z150 F3000\nG1 X500 Y0 Z150 A180 B0 C0 F1500\n"
       "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 F30\nG1 X200 Y0 Z100 A180 B0 C0 F3000\n")


def assert_refused_line_3_named(tmp_path, job: str) -> None:
    """``job`` through the installed command in a fresh process: exit 1, not "finished", frame 3 named."""
    (tmp_path / "job.txt").write_text(job)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", "sim://?clock=virtual"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 1 and summary["outcome"] != "finished", (done.stderr, summary)
    assert any("frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


@pytest.mark.timeout(60)
def test_the_same_job_through_the_installed_command_does_not_end_finished(tmp_path):
    assert_refused_line_3_named(tmp_path, JOB)
