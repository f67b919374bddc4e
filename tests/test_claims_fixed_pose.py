"""Issue 21 item 4: a job ending with ``POSE n`` on an arm whose fixed pose n is not the
profile's (here: where the arm already stands, so the POSE does not move it) is no sign of loss.

The arm runs to its own fixed pose; the profile's ``[poses]`` only describe it.  Before, the run
ended "frames were lost or cleared (a RESET CONNECTOR, a full buffer?)" though the simulator
dropped and cleared nothing; now the summary names the POSE line and the two poses.  The
simulated arm's own fixed poses come from its profile (``sim://?profile=``), the host's from the
built-in one.  Virtual time; the installed command in a fresh process.
"""

from __future__ import annotations

from importlib.resources import files

from claims_common import fresh


def test_a_pose_whose_motion_the_arm_does_not_report_is_named_not_called_loss(tmp_path):
    profile = files("armctl").joinpath("data/default_profile.toml").read_text(encoding="utf-8")
    arm_profile = profile.replace("0 = [0.0, 0.0, 0.0, 0.0, 90.0, 0.0]", "0 = [0.0, 30.0, 30.0, 0.0, 30.0, 0.0]")
    assert arm_profile != profile
    (tmp_path / "arm.toml").write_text(arm_profile, encoding="utf-8")
    # the arm starts at its own pose 0 (the host's pose 1); the job moves there, waits, then POSE 0
    (tmp_path / "job.txt").write_text("G6 J1=0 J2=30 J3=30 J4=0 J5=30 J6=0 S1500 F30\nG4 P200\nPOSE 0\n", encoding="utf-8")
    result = fresh(["-m", "armctl", "run", "job.txt", "--no-live", "--port",
                    f"sim://?clock=virtual&profile={tmp_path / 'arm.toml'}"], tmp_path)
    assert result.returncode == 1, (result.stdout, result.stderr)
    assert "lost" not in result.stdout + result.stderr and "cleared" not in result.stderr
    assert ("POSE 0 (line 3) should end at the profile's fixed pose 0 (joints 0.0, 0.0, 0.0, 0.0, 90.0, 0.0), but the "
            "arm stopped at joints (0.0, 30.0, 30.0, 0.0, 30.0, 0.0)") in result.stderr
    assert result.stderr.splitlines()[-1] == "stopped: no confirmation"
