"""Issue 21 item 4a and 4c: the loss checks reckon the first move from where the arm reports it is —
and no status kind reports the external axes E0/E1.

A job whose first line sets ``U240``, run a second time on the same arm: the arm's E0 stands at
240 already, the reported start pose takes the profile's 0 for it, so the plan gives the first
move 2.6 s (240° at 120°/s on an arm 1.3x slower) that the arm does not take.  With the probe's
``speed_tolerance`` of 1.05 the arm then "finished 8.6 % early" and the run ended "frames may
have been lost", last line known executed 2, though nothing was dropped (the issue's run: 7.9 %,
line 3).  The first move that sets E0/E1 now counts, in the loss checks' least motion, only what
it needs with the axes already at its targets.  Virtual time; one arm kept across the two runs
(in-process), and through the API in a fresh process.
"""

from __future__ import annotations

import re

from click.testing import CliRunner

from armctl.ui.cli import main
from claims_common import fresh
from test_resume_exactly_once import _open_one_arm

PROBED = "[connector]\nfifo_frames = 200\nspeed_factor = 1.3\nspeed_tolerance = 1.05\nkinematics_verified = true\n"
URL = "sim://?clock=virtual&speed_factor=1.3"


def _job() -> str:
    lines = ["G1 X210 Y0 Z300 A180 B0 C0 U240 S1500 F3000"]
    lines += [f"G1 X{210 + (k % 2) * 25} Y{(k % 5) * 5} Z{300 - (k % 3) * 10} F3000" for k in range(20)]
    return "\n".join(lines) + "\n"


def test_a_second_run_whose_axes_stand_at_the_first_target_is_done(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
    (tmp_path / "armctl.toml").write_text(PROBED, encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    for run in ("first", "second"):
        result = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", URL])
        assert result.exit_code == 0, (run, result.output)
        assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
        assert "lost" not in result.output
    assert ports[URL].model.frames_dropped == 0
    arm_s, estimated_s = map(float, re.search(r"arm time: ([\d.]+) s .*estimated ([\d.]+) s", result.stdout).groups())
    assert estimated_s - arm_s > 1.0  # the case: the plan's first move took no time on the arm


def test_the_same_through_the_api_in_a_fresh_process(tmp_path):
    (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
    (tmp_path / "armctl.toml").write_text(PROBED, encoding="utf-8")
    program = ("from armctl import Arm\n"
               f"with Arm.open(port={URL!r}) as arm:\n"
               "    for _ in range(2):\n"
               "        r = arm.run('job.txt')\n"
               "        print(r.outcome, r.arm_time_s < r.estimated_job_s - 1)\n")
    result = fresh(["-c", program], tmp_path)
    assert result.stdout.split("\n")[:2] == ["finished False", "finished True"], (result.stdout, result.stderr[-2000:])


def test_a_first_move_of_the_axes_from_farther_than_planned_is_no_sign_of_loss(tmp_path, monkeypatch):
    # Issue 21 item 4c, a loss claim only from evidence no timing error explains: the first run
    # leaves E0 at -240, the second's first move (after an M code and a delay, which time
    # confirms) sets U240 — 480 degrees the plan, from the profile's 0, takes for 240.  Before: "the
    # arm ran frame 3 at least 1.17x slower than the model, but the time bound allowed 1.05x …
    # frames may have been lost"; with only the slowness check mended, the time bound confirmed
    # frames while the arm was still on that move ("seen back on frame 12 … a frame already
    # finished").  Now its time is not known: no pace or slowness from it, and time never
    # confirms it (a later frame's sighting does).
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "armctl.toml").write_text(PROBED, encoding="utf-8")
    (tmp_path / "away.txt").write_text("G1 X210 Y0 Z300 A180 B0 C0 U-240 S1500 F3000\nG1 X250 Y0 Z250\n")
    job = ["M5", "G4 P300", "G1 X210 Y-60 Z250 A180 B0 C0 U240 S1500 F1500"]
    job += [f"G1 X{215 + (k % 2) * 25} Y{(k % 5) * 5} Z{250 - (k % 3) * 10} F3000" for k in range(10)]
    (tmp_path / "job.txt").write_text("\n".join(job) + "\n", encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    for name in ("away.txt", "job.txt"):
        result = CliRunner().invoke(main, ["run", name, "--no-live", "--port", URL])
        assert result.exit_code == 0, (name, result.output)
        assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert ports[URL].model.frames_dropped == 0
