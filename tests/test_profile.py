"""Profile loading: where a profile comes from, how partial ones merge, and every error message."""

import tomllib
from importlib import resources

import pytest

from armctl.errors import ConfigError, ProfileError
from armctl.host.profile import (
    Profile, default_profile, find_config, load_profile, parse_profile, read_toml,
)


def write(path, text: str):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


# --- the packaged default ----------------------------------------------------------------------


def test_default_profile_is_complete_and_cached():
    profile = default_profile()
    assert isinstance(profile, Profile)
    assert profile is default_profile()
    assert len(profile.joint_limits_deg) == 6 and len(profile.poses) == 4
    assert all(len(pose) == 6 for pose in profile.poses)
    assert profile.pwm.channels == (1,)
    assert len(profile.timing.joint_ramp_s) == 6
    assert profile.lint.end_gripper is None and profile.lint.end_paused is None


def test_default_profile_marks_its_numbers_illustrative():
    text = resources.files("armctl.data").joinpath("default_profile.toml").read_text(encoding="utf-8")
    assert "ILLUSTRATIVE" in text
    for line in text.splitlines():  # every number in a [links] / [speed] / [timing] line says so
        if line and line[0].isalpha() and "=" in line and any(ch.isdigit() for ch in line.split("=", 1)[1]):
            assert "illustrative" in line or "protocol" in line or "document" in line, line


def test_default_fixed_poses_lie_inside_the_joint_limits_and_workspace():
    profile = default_profile()
    for pose in profile.poses:
        x, y, z = profile.kinematics.forward(pose)[:3]
        assert profile.workspace.x_mm[0] <= x <= profile.workspace.x_mm[1]
        assert profile.workspace.z_mm[0] <= z <= profile.workspace.z_mm[1]


def test_timing_ramp_by_smoothing_level():
    timing = parse_profile({"timing": {"joint_ramp_s": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]}}).timing
    assert [timing.ramp_s(level) for level in range(7)] == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6]


# --- where a profile comes from ----------------------------------------------------------------


def test_explicit_file_merges_over_the_default(tmp_path):
    path = write(tmp_path / "arm.toml", "[speed]\nmax_joint_deg_s = 45\n")
    profile = load_profile(path)
    assert profile.speed.max_joint_deg_s == 45.0
    assert profile.speed.max_linear_mm_min == default_profile().speed.max_linear_mm_min  # same section, kept
    assert profile.links == default_profile().links
    assert profile.source == str(path)


def test_without_armctl_toml_the_default_is_used(tmp_path):
    assert load_profile(start=tmp_path) == default_profile()
    assert find_config(tmp_path) == (None, {})


def test_profile_table_of_armctl_toml_found_walking_up(tmp_path):
    config = write(tmp_path / "armctl.toml", 'port = "/dev/ttyUSB0"\nbaud = 115200\n[profile.speed]\nattitude_deg_s = 30\n')
    deep = tmp_path / "jobs" / "today"
    deep.mkdir(parents=True)
    assert load_profile(start=deep).speed.attitude_deg_s == 30.0
    path, data = find_config(deep)
    assert path == config.resolve()
    assert data["port"] == "/dev/ttyUSB0" and data["baud"] == 115200  # the whole file, for other readers


def test_profile_path_is_relative_to_armctl_toml(tmp_path):
    write(tmp_path / "armctl.toml", 'profile = "arms/mine.toml"\n')
    write(tmp_path / "arms" / "mine.toml", 'name = "mine"\n[pwm]\nchannels = [1, 2]\n')
    sub = tmp_path / "scripts"
    sub.mkdir()
    profile = load_profile(start=sub)
    assert profile.name == "mine" and profile.pwm.channels == (1, 2)


def test_explicit_file_wins_over_armctl_toml(tmp_path):
    write(tmp_path / "armctl.toml", "[profile.speed]\nattitude_deg_s = 30\n")
    explicit = write(tmp_path / "other.toml", "[speed]\nattitude_deg_s = 60\n")
    assert load_profile(explicit, start=tmp_path).speed.attitude_deg_s == 60.0


def test_lint_options(tmp_path):
    profile = parse_profile({"lint": {"end_gripper": "open", "end_paused": False}})
    assert profile.lint.end_gripper == "open" and profile.lint.end_paused is False


def test_fixed_poses_and_joint_limits_read_from_toml(tmp_path):
    path = write(tmp_path / "p.toml", "[joints]\nj2_deg = [-80, 80]\n[poses]\n1 = [10, 20, 30, 0, 40, 0]\n")
    profile = load_profile(path)
    assert profile.joint_limits_deg[1] == (-80.0, 80.0)
    assert profile.poses[1] == (10.0, 20.0, 30.0, 0.0, 40.0, 0.0)
    assert profile.poses[0] == default_profile().poses[0]


# --- errors ---------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(ProfileError, match=r"nope\.toml: file not found"):
        load_profile(tmp_path / "nope.toml")


def test_missing_file_named_by_armctl_toml(tmp_path):
    write(tmp_path / "armctl.toml", 'profile = "gone.toml"\n')
    with pytest.raises(ProfileError, match=r"gone\.toml: file not found"):
        load_profile(start=tmp_path)


def test_bad_toml_names_line_and_column(tmp_path):
    path = write(tmp_path / "bad.toml", "[speed]\nmax_joint_deg_s = = 3\n")
    with pytest.raises(ProfileError, match=r"bad\.toml:2:19: invalid TOML: "):
        load_profile(path)


def test_bad_armctl_toml(tmp_path):
    write(tmp_path / "armctl.toml", "port = \n")
    with pytest.raises(ProfileError, match=r"armctl\.toml:1:\d+: invalid TOML: "):
        find_config(tmp_path)


def test_not_utf8(tmp_path):
    path = tmp_path / "latin.toml"
    path.write_bytes(b'name = "caf\xe9"\n')
    with pytest.raises(ProfileError, match=r"latin\.toml: not UTF-8"):
        load_profile(path)


@pytest.mark.parametrize(
    "text, message",
    [
        ("[speed]\nmax_joint_deg_s = \"fast\"\n", r"speed\.max_joint_deg_s must be a number, not 'fast'"),
        ("[speed]\nmax_joint_deg_s = true\n", r"speed\.max_joint_deg_s must be a number, not True"),
        ("[speed]\nmax_joint_deg_s = -5\n", r"speed\.max_joint_deg_s must be from 0\.1 to 3600, not -5"),
        ("[joints]\nj3_deg = [50, -50]\n", r"joints\.j3_deg has min 50 > max -50"),
        ("[workspace]\nz_mm = [10]\n", r"workspace\.z_mm must be a \[min, max\] pair"),
        ("[speed]\nmax_jont_deg_s = 5\n", r"unknown key 'speed\.max_jont_deg_s' \(did you mean 'max_joint_deg_s'\?\)"),
        ("[sped]\n", r"unknown key 'sped' \(did you mean 'speed'\?\)"),
        ("speed = 3\n", r"speed must be a table"),
        ("[poses]\n4 = [0, 0, 0, 0, 0, 0]\n", r"unknown key 'poses\.4'"),
        ("[poses]\n0 = [0, 0, 0]\n", r"poses\.0 must be a list of 6 numbers"),
        ("[poses]\n0 = [0, 0, 0, 0, 170, 0]\n", r"poses\.0 has J5 = 170, outside joints\.j5_deg"),
        ("[pwm]\nchannels = [1, 5]\n", r"pwm\.channels must be a non-empty list of distinct PWM channels"),
        ("[pwm]\ngripper_close_us = 3000\n", r"pwm\.gripper_close_us must be from 500 to 2500, not 3000"),
        ("[pwm]\nrange_us = [1000, 1800]\n", r"pwm\.gripper_close_us = 2000 is outside pwm\.range_us"),
        ("[pwm]\nrange_us = [400, 2500]\n", r"pwm\.range_us must be from 500 to 2500, not 400"),
        ("[timing]\npose_smoothing = 7\n", r"timing\.pose_smoothing must be a whole number 0…6"),
        ("[timing]\njoint_ramp_s = [0.1, 0.2]\n", r"timing\.joint_ramp_s must be a list of 6 numbers"),
        ("[timing]\npwm_change_s = -1\n", r"timing\.pwm_change_s must be from 0 to 60, not -1"),
        ("[lint]\nend_gripper = \"ajar\"\n", r"lint\.end_gripper must be \"open\" or \"closed\""),
        ("[lint]\nend_paused = 0\n", r"lint\.end_paused must be true or false"),
        ("name = 3\n", r"name must be a string"),
    ],
)
def test_each_error_names_the_file_and_key(tmp_path, text, message):
    path = write(tmp_path / "arm.toml", text)
    with pytest.raises(ProfileError, match=rf"arm\.toml: {message}"):
        load_profile(path)


def test_errors_in_the_profile_table_name_armctl_toml_and_the_full_key(tmp_path):
    write(tmp_path / "armctl.toml", "[profile.speed]\nmax_joint_deg_s = 0\n")
    with pytest.raises(ProfileError, match=r"armctl\.toml: profile\.speed\.max_joint_deg_s must be from 0\.1 to 3600, not 0"):
        load_profile(start=tmp_path)


def test_profile_entry_of_the_wrong_type(tmp_path):
    write(tmp_path / "armctl.toml", "profile = 3\n")
    with pytest.raises(ConfigError, match=r"armctl\.toml: profile = 3 must be a table \(\[profile\]\) or a path"):
        load_profile(start=tmp_path)


def test_directory_instead_of_file(tmp_path):
    with pytest.raises(ProfileError, match="a directory, not a regular file"):  # issue 22: refused before it is opened
        load_profile(tmp_path)


def test_read_toml_returns_plain_dicts(tmp_path):
    path = write(tmp_path / "x.toml", "a = 1\n[b]\nc = [1, 2]\n")
    assert read_toml(path) == tomllib.loads("a = 1\n[b]\nc = [1, 2]\n")
