"""A finding is only as true as the numbers it rests on (issue 10, "Findings that are not true").

The built-in profile's link lengths, joint limits, workspace and speeds are illustrative: a
finding on them is a warning that says so and never blocks ``run``.  The protocol's own ranges
(PWM 500–2500 µs, acceleration 3200 mm/s², the wired PWM channel) and any number the user's
profile gives keep their error.  One mistake is one finding: a pose is judged once per change.
"""

from __future__ import annotations

import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.lint import lint_lines
from armctl.host.profile import ILLUSTRATIVE, PROTOCOL, default_profile, load_profile, parse_profile

FAST_SIM = "sim://?clock=virtual"
TIMEOUT_S = 60  # bounds a hang on a loaded machine; not a speed assertion
NOTE = "illustrative numbers from the built-in profile; give your arm's profile with --profile"

# A pick-and-place at the pose of the issue: J5 would be 144°, past the illustrative ±120°.
PICK_AND_PLACE = """\
; pick and place with the tool tilted (A0 B30 C0)
G1 X200 Y0 Z250 A0 B30 C0 S1000 F3000
G1 Z180
G1 S2000
G1 Z250
G1 Y60
G1 Z180
G1 S1000
G1 Z250
"""


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ARMCTL_PORT", "")


def measured_profile(tmp_path: Path) -> Path:
    """The packaged numbers given as the user's own profile: every key measured (by the user)."""
    path = tmp_path / "measured.toml"
    path.write_bytes(resources.files("armctl.data").joinpath("default_profile.toml").read_bytes())
    return path


def lint(text: str, profile=None):
    return lint_lines(text.splitlines(), "job.txt", profile or default_profile())


def findings(text: str, profile=None) -> list[tuple[int, str, str]]:
    return [(d.span.line, d.code, d.severity) for d in lint(text, profile).diagnostics]


# --- where each number comes from -------------------------------------------------------------------


def test_the_packaged_profile_knows_which_numbers_are_illustrative():
    profile = default_profile()
    assert profile.source_of("links.upper_arm_mm") == ILLUSTRATIVE
    assert profile.source_of("joints.j5_deg") == ILLUSTRATIVE
    assert profile.source_of("pwm.range_us") == PROTOCOL
    assert profile.source_of("speed.max_accel_mm_s2") == PROTOCOL
    assert profile.illustrative(["links", "pwm.range_us", "workspace.reach_mm"]) == ["links", "workspace.reach_mm"]


def test_a_users_profile_names_the_keys_it_gives(tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text("[joints]\nj5_deg = [-150.0, 150.0]\n")
    profile = load_profile(path)
    assert profile.source_of("joints.j5_deg") == str(path)
    assert profile.source_of("joints.j4_deg") == ILLUSTRATIVE  # laid over the packaged default
    assert profile.illustrative(["joints.j5_deg"]) == [] and profile.illustrative(["joints"]) == ["joints"]
    table = parse_profile({"links": {"tool_mm": 50.0}}, "armctl.toml", prefix="profile.")
    assert table.source_of("links.tool_mm") == "armctl.toml"


# --- illustrative numbers make warnings, measured ones errors --------------------------------------


def test_the_issues_pose_is_a_warning_that_names_its_source_and_the_attitude():
    (diagnostic,) = lint("G1 X200 Y0 Z180 A0 B30 C0 S1000 F3000").diagnostics
    assert (diagnostic.code, diagnostic.severity) == ("L103", "warning")
    assert "J5 = 144" in diagnostic.message and NOTE in diagnostic.message
    assert "not with the attitude A0 B30 C0" in diagnostic.hint  # the cause: attitude, not distance


def test_the_same_pose_on_the_users_own_numbers_is_an_error(tmp_path):
    (diagnostic,) = lint("G1 X200 Y0 Z180 A0 B30 C0 S1000 F3000", load_profile(measured_profile(tmp_path))).diagnostics
    assert (diagnostic.code, diagnostic.severity) == ("L103", "error")
    assert "illustrative" not in diagnostic.message


def test_a_point_out_of_reach_says_distance_not_attitude(tmp_path):
    profile = load_profile(measured_profile(tmp_path))
    # inside the box and the reach radius, but no attitude reaches it (even tool down)
    (diagnostic,) = lint("G1 X0 Y0 Z-15 A180 B0 C0 S1000 F3000", profile).diagnostics
    assert diagnostic.code == "L103" and "out of the arm's reach" in diagnostic.hint


def test_the_issues_grid_of_poses_has_no_error_on_the_built_in_profile():
    lines = [f"G1 X200 Y0 Z{z} A{a} B{b} C{c} S1000 F3000" for z in range(150, 251, 20)
             for a in (0, 90, 180) for b in (0, 30, 60) for c in (0, 90)]
    report = lint("\n".join(lines))
    assert report.errors == 0
    assert report.warnings > 0  # some of them the illustrative limits do dislike


@pytest.mark.parametrize("script, code", [
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F9000", "L201"),  # speed.max_linear_mm_min
    ("G6 J1=0 J2=120 J3=0 J4=0 J5=90 J6=0 S1000 F30", "L104"),  # joints.j2_deg
    ("G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F3000", "L202"),  # speed.max_joint_deg_s
    ("G1 X500 Y0 Z150 A180 B0 C0 S1000 F3000", "L103"),  # workspace
])
def test_findings_on_illustrative_numbers_are_warnings_and_errors_on_the_users(tmp_path, script, code):
    assert findings(script) == [(1, code, "warning")]
    assert findings(script, load_profile(measured_profile(tmp_path))) == [(1, code, "error")]


@pytest.mark.parametrize("script, code", [
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG220 X260 K3000 F3000", None),
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000 T2", "L301"),  # pwm.channels: the protocol's
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG300 X260 Y10 Z150 R10\nG301 X250 Y0 Z150", "L101"),  # geometry
])
def test_findings_on_the_protocol_or_geometry_stay_errors(script, code):
    assert [c for _, c, severity in findings(script) if severity == "error"] == ([code] if code else [])


# --- one mistake, one finding ----------------------------------------------------------------------


def test_a_pose_is_judged_once_per_change_of_the_pose(tmp_path):
    script = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X500\nG1 S2000\nG1 F1000\nG1 S1000\nG1 F2000\nG1 X250\nG1 X500\n"
    profile = load_profile(measured_profile(tmp_path))
    assert [(line, code) for line, code, _ in findings(script, profile)] == [(2, "L103"), (8, "L103")]


def test_a_loop_that_returns_to_a_bad_pose_is_still_reported_once_per_line(tmp_path):
    script = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nO1 repeat [3]\nG1 X500\nG1 X250\nO1 endrepeat\n"
    profile = load_profile(measured_profile(tmp_path))
    assert [(line, code) for line, code, _ in findings(script, profile)] == [(3, "L103")]


# --- run accepts what the illustrative profile merely dislikes --------------------------------------


def test_run_streams_a_pick_and_place_the_illustrative_profile_dislikes(tmp_path):
    """Sent whole.  The simulated arm has the same illustrative limits, so it refuses the J5 = 144°
    targets (lines 3, 4, 7, 8: armctl/sim/executor.py) — and with the arm standing at Z250, the
    end of line 5 too, no sign saw it: the job ended "finished", exit 0.  A move whose target the
    profile's kinematics cannot take needs the reports' proof that it ran (``Sightings.may_refuse``)."""
    path = tmp_path / "pick.txt"
    path.write_text(PICK_AND_PLACE)
    result = CliRunner().invoke(main, ["run", str(path), "--port", FAST_SIM, "--no-live"])
    assert result.exit_code == 1, result.output
    assert "frames: 8 of 8 sent" in result.stdout
    assert result.stdout.splitlines()[-1].startswith("finished, unproven:")
    assert "no report showed the arm run frame 2 (line 3), frame 6 (line 7)" in result.stderr
    assert f"{path}:3:1: L103 " in result.stderr and NOTE in result.stderr
    assert "nothing was sent" not in result.stderr


def test_run_refuses_the_same_job_against_the_users_own_profile(tmp_path):
    path = tmp_path / "pick.txt"
    path.write_text(PICK_AND_PLACE)
    result = CliRunner().invoke(main, ["run", str(path), "--port", FAST_SIM, "--no-live",
                                       "--profile", str(measured_profile(tmp_path))])
    assert result.exit_code == 1 and "nothing was sent to the arm" in result.stderr


def test_lint_and_run_through_the_installed_command(tmp_path):
    path = tmp_path / "pick.txt"
    path.write_text(PICK_AND_PLACE)
    linted = subprocess.run([sys.executable, "-m", "armctl", "lint", str(path)], cwd=tmp_path, capture_output=True,
                            text=True, timeout=TIMEOUT_S)
    assert linted.returncode == 0 and "Found 2 warnings in 1 of 1 file." in linted.stdout
    ran = subprocess.run([sys.executable, "-m", "armctl", "run", str(path), "--port", FAST_SIM, "--no-live"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=TIMEOUT_S,
                         env={**__import__("os").environ, "ARMCTL_PORT": ""})
    assert ran.returncode == 1, ran.stderr  # the simulated arm refuses the J5 = 144° targets (above)
    assert "finished, unproven:" in ran.stdout and "nothing was sent" not in ran.stderr
