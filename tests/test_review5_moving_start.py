"""Review of the wait for an arm still moving when a job starts (jobflow.read_arm), as a user of a
real arm meets it: a noisy status line, an arm left moving very slowly.

The status line has no checksum (PROTOCOL.md H9): a corrupted report within the arm's reach passes
the reader's plausibility test.  When the first report read is such a one, the pose it gives
differs from every later one, and ``read_arm`` took a still arm for a moving one: "the arm is
moving (frames queued before this job still running? ...)" on a freshly started, idle arm
(``sim://?clock=virtual&corrupt=0.15``: 6 seeds of 1-20 through the installed command; 0.05: 3 of
20; 0.02: 1 of 20).  The job still finished; the note was false.  The simulator's own record
(``execution_log``: nothing ran before the job) is the truth."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.timeout(60)

JOB = "G90\nG1 X360 Y0 Z150 A180 B0 C0 S1000 F3000\nG6 J1=-7.6 J2=11.4 J3=-7.9 J4=0 J5=90 J6=0 F30\n"
WAITING = "waiting for it to come to rest"
FALSE_NOTE_SEEDS = (1, 2, 11, 12, 18, 19)  # corrupt=0.15: the seeds of 1-20 whose first report read was corrupted


def _run_installed(tmp_path, url: str) -> subprocess.CompletedProcess:
    (tmp_path / "job.txt").write_text(JOB)
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")  # no probe record of another test's arm
    return subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--port", url], cwd=tmp_path,
                          capture_output=True, text=True, timeout=50, env=env)


@pytest.mark.xfail(strict=True, reason="read_arm takes a corrupted first report for motion: a false 'the arm is "
                                       "moving' note on a still arm")
@pytest.mark.parametrize("seed", FALSE_NOTE_SEEDS)
def test_a_still_arm_on_a_noisy_line_is_not_said_to_be_moving(tmp_path, seed):
    done = _run_installed(tmp_path, f"sim://?clock=virtual&corrupt=0.15&seed={seed}")
    assert done.returncode == 0 and "finished: the arm finished the job" in done.stderr, done.stderr
    assert WAITING not in done.stderr, done.stderr
