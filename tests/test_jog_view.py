"""The jog panel rendered to text (armctl/jog/view.py), as the style guide asks: a recording
``Console(width=…, color_system=None)`` and a comparison of the exported text."""

from __future__ import annotations

from rich.console import Console

from armctl.jog.keymap import default_keymap, keymap_from_config
from armctl.jog.moves import Reported
from armctl.jog.session import JogView
from armctl.jog.view import render_jog

GRIPPER = (1000.0, 2000.0)
POSE = Reported((182.2, 83.9, 265.2), (180.0, 11.34, 24.71), (24.71, 0.0, 11.34, 0.0, 90.0, 0.0), 1000.0, (0, 0, 0))


def _view(**changes) -> JogView:
    values = dict(mode="joint", level=2, levels=3, stepping=False, paused=False, moving="J1+", busy=None,
                  message="speed level 2", recorded=3, record_path="poses.txt", step_size="5 deg",
                  speed="30 deg/s", joystick_value=188, url="sim://")
    values.update(changes)
    return JogView(**values)


def _text(renderable, width: int = 90) -> str:
    console = Console(record=True, width=width, color_system=None)
    console.print(renderable)
    return console.export_text()


JOINT_PANEL = """\
╭────────── armctl jog · joint mode · continuous · level 2/3 ──────────╮
│ X Y Z mm   182.2  83.9  265.2                                        │
│ A B C deg  180.00  11.34  24.71                                      │
│ J1…J6 deg  24.71  0.00  11.34  0.00  90.00  0.00                     │
│ gripper    1000 µs (open)                                            │
│ arm        running                                                   │
│ jog        J1+ (joystick ±60)                                        │
│ level      2/3: step 5 deg, F 30 deg/s                               │
│ recording  poses.txt (3 poses)                                       │
│ » speed level 2                                                      │
│                                                                      │
│ keys (joint mode)                                                    │
│   q/a J1 +/−              w/s J2 +/−              e/d J3 +/−         │
│   r/f J4 +/−              t/g J5 +/−              y/h J6 +/−         │
│     m joint ↔ linear      Tab continuous ↔ step   +/= speed level up │
│     - speed level down      o gripper open          c gripper close  │
│ space stop now              p pause / resume    Enter record pose    │
│ x/Esc quit             Ctrl-C quit (exit 130)                        │
╰─────────────────────────────── sim:// ───────────────────────────────╯
"""

LINEAR_PANEL = """\
╭────────────── armctl jog · linear mode · step · level 1/3 ───────────────╮
│ X Y Z mm   —  —  —                                                       │
│ A B C deg  —  —  —                                                       │
│ J1…J6 deg  —  —  —  —  —  —                                              │
│ gripper    —                                                             │
│ arm        PAUSED (p resumes)                                            │
│ jog        still · waiting: step X+ 1 mm                                 │
│ level      1/3: step 1 mm, F 600 mm/min                                  │
│                                                                          │
│ keys (linear mode)                                                       │
│   ↑/↓ X +/−               ←/→ Y +/−             PgUp/PgDn Z +/−          │
│     m joint ↔ linear      Tab continuous ↔ step       +/= speed level up │
│     - speed level down      o gripper open              c gripper close  │
│ space stop now              p pause / resume        Enter record pose    │
│ x/Esc quit             Ctrl-C quit (exit 130)                            │
╰───────────────────────────────── sim:// ─────────────────────────────────╯
"""


def test_joint_mode_panel():
    assert _text(render_jog(_view(), POSE, 1000, default_keymap(), GRIPPER)) == JOINT_PANEL


def test_linear_step_mode_panel_before_the_arm_reported_paused():
    view = _view(mode="linear", level=1, stepping=True, paused=True, moving=None, busy="step X+ 1 mm", message="",
                 record_path=None, step_size="1 mm", speed="600 mm/min")
    assert _text(render_jog(view, None, None, default_keymap(), GRIPPER)) == LINEAR_PANEL


def test_the_panel_shows_the_configured_keys():
    keymap = keymap_from_config({"j1_plus": "u", "j1_minus": "j", "quit": ["Q"]})
    text = _text(render_jog(_view(), POSE, 1500, keymap, GRIPPER))
    assert "u/j J1 +/−" in text and "Q quit" in text and "x/Esc" not in text
    assert "gripper    1500 µs " in text and "(open)" not in text  # neither open nor closed


def test_the_panel_fits_a_narrow_terminal_without_crashing():
    text = _text(render_jog(_view(), POSE, 1000, default_keymap(), GRIPPER), width=40)
    assert "armctl jog" in text and "J1+" in text


def test_a_reading_that_rounds_to_zero_shows_no_minus_sign():
    # the arm reported B = -0.001 (a wrist at zero, within its noise): the panel showed B -0.00
    pose = Reported((182.2, -0.004, 265.2), (180.0, -0.001, 24.71), (-0.003, 0.0, 11.34, 0.0, 90.0, 0.0), 1000.0, (0, 0, 0))
    text = _text(render_jog(_view(), pose, 1000, default_keymap(), GRIPPER))
    assert "-0.00" not in text and "-0.0 " not in text, text
    assert "0.00" in text
