"""armctl.toml's [jog] and [jog.keys] tables, and the teach line format (armctl/jog/settings.py,
keymap.py, teach.py)."""

from __future__ import annotations

import tomllib
from datetime import datetime, timedelta, timezone

import pytest

from armctl.jog.keymap import DEFAULT_KEYS, JogConfigError, default_keymap, keymap_from_config
from armctl.jog.moves import Reported
from armctl.jog.settings import JogSettings, settings_from_config
from armctl.jog.teach import number, taught_line
from armctl.script import compile_text

WHEN = datetime(2024, 5, 1, 14, 30, 5, tzinfo=timezone(timedelta(hours=2)))


def test_default_key_map_is_the_issues():
    keymap = default_keymap()
    joint = {key: keymap.action(key, "joint") for key in "qawsedrftgyh"}
    assert joint == {
        "q": "j1_plus", "a": "j1_minus", "w": "j2_plus", "s": "j2_minus", "e": "j3_plus", "d": "j3_minus",
        "r": "j4_plus", "f": "j4_minus", "t": "j5_plus", "g": "j5_minus", "y": "j6_plus", "h": "j6_minus",
    }
    linear = {key: keymap.action(key, "linear") for key in ("up", "down", "left", "right", "pageup", "pagedown")}
    assert linear == {"up": "x_plus", "down": "x_minus", "left": "y_plus", "right": "y_minus",
                      "pageup": "z_plus", "pagedown": "z_minus"}
    common = {"m": "mode", "+": "faster", "-": "slower", "o": "open", "c": "close", "space": "stop", "p": "pause",
              "enter": "record", "x": "quit", "esc": "quit", "tab": "step"}
    for mode in ("joint", "linear"):
        assert {key: keymap.action(key, mode) for key in common} == common
    assert keymap.action("q", "linear") is None and keymap.action("up", "joint") is None


def test_keys_table_rebinds_named_actions_only():
    table = tomllib.loads('j1_plus = "u"\nj1_minus = "j"\nquit = ["x", "esc", "Q"]\n')
    keymap = keymap_from_config(table)
    assert keymap.action("u", "joint") == "j1_plus" and keymap.action("q", "joint") is None
    assert keymap.action("Q", "linear") == "quit"
    assert keymap.keys_for("j2_plus") == DEFAULT_KEYS["j2_plus"]


def test_a_key_may_mean_different_things_in_the_two_modes():
    keymap = keymap_from_config({"x_plus": "q"})
    assert keymap.action("q", "linear") == "x_plus" and keymap.action("q", "joint") == "j1_plus"


@pytest.mark.parametrize("table, fragment", [
    ({"jump": "j"}, "unknown action"),
    ({"quit": "ctrl-x"}, "not a key name"),
    ({"quit": []}, "key name or a list"),
    ({"quit": 3}, "key name or a list"),
    ({"j1_plus": "w"}, "bound to both"),
    ({"stop": "x"}, "bound to both"),
])
def test_bad_keys_tables_name_the_problem(table, fragment):
    with pytest.raises(JogConfigError, match=fragment):
        keymap_from_config(table, "/cfg/armctl.toml")


def test_jog_table_overrides_timings_and_levels():
    table = tomllib.loads(
        "initial_delay_ms = 600\nrepeat_gap_ms = 80\nlevel = 2\n"
        "joystick_offsets = [30, 60, 90, 120]\nstep_mm = [0.5, 1, 5, 10]\nstep_deg = [0.5, 1, 5, 10]\n"
        "linear_speed_mm_min = [300, 600, 1500, 3000]\njoint_speed_deg_s = [5, 10, 30, 60]\n"
        "[keys]\nquit = \"x\"\n"
    )
    settings = settings_from_config(table)
    assert settings.initial_delay_ms == 600 and settings.repeat_gap_ms == 80 and settings.levels == 4
    assert settings.level == 2 and settings.step_mm[0] == 0.5


def test_defaults_have_three_levels_of_1_5_10():
    settings = settings_from_config({})
    assert settings == JogSettings()
    assert settings.levels == 3 and settings.step_mm == (1, 5, 10) and settings.step_deg == (1, 5, 10)


@pytest.mark.parametrize("table, fragment", [
    ({"repeat_gap_ms": 200}, "repeat_gap_ms"),  # the neutral must stay within 150 ms of the last repeat
    ({"initial_delay_ms": "500"}, "initial_delay_ms"),
    ({"joystick_offsets": [10, 60, 110]}, "outside the still band"),
    ({"joystick_offsets": [30, 60, 130]}, "21…127"),
    ({"step_mm": [1, 5]}, "same length"),
    ({"level": 4}, "only 3 levels"),
    ({"speed": 3}, "not a jog setting"),
    ({"step_deg": [1, -5, 10]}, "positive"),
])
def test_bad_jog_tables_name_the_key(table, fragment):
    with pytest.raises(JogConfigError, match=fragment):
        settings_from_config(table, "/cfg/armctl.toml")


@pytest.mark.parametrize("value, digits, text", [
    (210.0, 1, "210"), (-0.04, 1, "0"), (12.345, 2, "12.35"), (-7.5, 1, "-7.5"), (1500.0, 0, "1500"), (0.0, 2, "0"),
])
def test_numbers_drop_trailing_zeros(value, digits, text):
    assert number(value, digits) == text


POSE = Reported((210.0, -12.34, 300.05), (180.0, -0.0, 24.71), (24.71, 0.0, 11.34, 0.0, 90.0, 0.0), 1000.0, (0, 0, 0))


def test_joint_mode_teaches_a_complete_g6_line():
    assert taught_line("joint", POSE, 30.0, WHEN) == (
        "G6 J1=24.71 J2=0 J3=11.34 J4=0 J5=90 J6=0 S1000 F30 ; taught 2024-05-01T14:30:05+02:00\n"
    )


def test_linear_mode_teaches_a_complete_g1_line():
    assert taught_line("linear", POSE, 1500.0, WHEN) == (
        "G1 X210 Y-12.3 Z300.1 A180 B0 C24.71 S1000 F1500 ; taught 2024-05-01T14:30:05+02:00\n"
    )


@pytest.mark.parametrize("modes", [("joint", "linear"), ("linear", "joint"), ("linear",), ("joint",)])
def test_taught_files_compile_without_diagnostics_in_any_order(modes):
    text = "".join(taught_line(mode, POSE, 30.0 if mode == "joint" else 1500.0, WHEN) for mode in modes)
    compilation = compile_text(text, "taught.txt")
    assert len(list(compilation)) == len(modes)
    assert compilation.finish() == []


def test_armctl_config_checks_the_jog_table_as_jog_reads_it(tmp_path):
    # `armctl config` listed {"step_mm": -1} as a setting, exit 0, while `armctl jog` refuses it
    # (found by a review): both read the table with jog.settings.jog_from_config
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    (tmp_path / "armctl.toml").write_text("[jog]\nstep_mm = -1\n")
    bad = subprocess.run([sys.executable, "-m", "armctl", "config"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=50)
    assert bad.returncode == 2 and "jog.step_mm must be a non-empty list" in bad.stderr, bad.stderr
    (tmp_path / "armctl.toml").write_text('[jog]\ninitial_delay_ms = 400\n\n[jog.keys]\nquit = ["Q"]\n')
    good = subprocess.run([sys.executable, "-m", "armctl", "config"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=50)
    assert good.returncode == 0 and '"initial_delay_ms": 400' in good.stdout, good.stdout + good.stderr
    (tmp_path / "armctl.toml").write_text('[lint]\nselect = ["X9"]\n')  # and [lint] as armctl lint reads it
    bad = subprocess.run([sys.executable, "-m", "armctl", "config"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=50)
    assert bad.returncode == 2 and "lint.select: unknown rule code or prefix 'X9'" in bad.stderr, bad.stderr
