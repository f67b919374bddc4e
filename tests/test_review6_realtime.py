"""Review of the arm on the wall clock (session 6), as someone with a real arm on their desk meets
it: the installed command in fresh processes, against ``armctl sim --pty`` where the fault needs
the wall clock, in virtual time where it does not.

- The ETA of a line-bound job: 301 moves of 4 ms each at 9600 baud take 15.1 s (the line carries a
  frame every 50 ms), and ``run`` said ``ETA 0:01`` two seconds in (``eta_s`` 1.02 at 2.58 s in
  ``--json``): the ETA counted the motion still unsent (3.2 s in all) and never the line it has to
  cross.  Now it is at least the unsent frames' time on the line.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.timeout(60)


def _env(tmp_path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")  # no probe record of another test's arm
    return env


def _tiny_job(tmp_path, moves: int = 300):
    """``moves`` moves of 0.2 mm (4 ms each at 3000 mm/min): line-bound, a frame every 50 ms."""
    lines = ["G1 X200 Y0 Z200 A180 B0 C0 S1500 F3000"] + [f"G1 X{200.2 if i % 2 == 0 else 200}" for i in range(moves)]
    path = tmp_path / "tiny.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_eta_of_a_line_bound_job_counts_the_line(tmp_path):
    script = _tiny_job(tmp_path)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", "sim://?clock=virtual", "--json"],
                          capture_output=True, text=True, timeout=50, env=_env(tmp_path), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in done.stdout.splitlines()]
    estimated_s = events[0]["estimated_job_s"]
    assert estimated_s == pytest.approx(15.1, abs=0.1)
    progress = [event for event in events if event["event"] == "progress"]
    assert len(progress) > 10
    for event in progress:  # elapsed + ETA: the job's time, whenever it is read (the arm keeps the model's pace)
        left_frames = event["total_frames"] - event["frames_sent"]
        assert event["eta_s"] >= left_frames * 0.05 - 1e-6, event
        assert event["elapsed_s"] + event["eta_s"] == pytest.approx(estimated_s, rel=0.1), event
