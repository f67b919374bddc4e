"""The jog panel: pose, joints, gripper, mode, speed level, step/continuous and the key map.

Strategy: a pure function of plain data — the session's ``JogView``, the reported pose and the
key map — returning a rich renderable, so tests render it to a recording
``Console(width=…, color_system=None)`` and compare text.  The edge owns the ``Live`` and how
often it refreshes.
"""

from __future__ import annotations

from rich.console import Group
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from .keymap import ACTIONS, JOINT, LINEAR, KeyMap
from .moves import Reported
from .session import JogView

KEY_LABELS = {
    "up": "↑", "down": "↓", "left": "←", "right": "→", "pageup": "PgUp", "pagedown": "PgDn", "enter": "Enter",
    "esc": "Esc", "space": "space", "tab": "Tab", "backspace": "Bksp", "home": "Home", "end": "End",
    "insert": "Ins", "delete": "Del",
}
_AXES = {JOINT: [f"j{k}" for k in range(1, 7)], LINEAR: ["x", "y", "z"]}
_COMMON = ("mode", "step", "faster", "slower", "open", "close", "stop", "pause", "record", "quit")


def key_label(name: str) -> str:
    return KEY_LABELS.get(name, name)


def _keys(keymap: KeyMap, action: str) -> str:
    return "/".join(key_label(k) for k in keymap.keys_for(action)) or "—"


def _num(value, digits: int) -> str:
    # ("z": a reading that rounds to zero shows 0.00, not -0.00 — the arm at B=-0.001 is at 0)
    return "—" if value is None else f"{value:z.{digits}f}"


def _gripper(pwm_us, gripper_us: tuple[float, float]) -> str:
    if pwm_us is None:
        return "—"
    names = [name for name, value in zip(("open", "closed"), gripper_us) if abs(pwm_us - value) < 1]
    return f"{pwm_us:g} µs" + (f" ({names[0]})" if names else "")


def _pose_table(view: JogView, pose: Reported | None, state_pwm, gripper_us) -> Table:
    table = Table.grid(padding=(0, 2))
    table.add_column(style="bold", no_wrap=True)
    table.add_column()
    xyz = pose.xyz_mm if pose else (None,) * 3
    attitude = pose.attitude_deg if pose else (None,) * 3
    joints = pose.joints_deg if pose else (None,) * 6
    table.add_row("X Y Z mm", "  ".join(_num(v, 1) for v in xyz))
    table.add_row("A B C deg", "  ".join(_num(v, 2) for v in attitude))
    table.add_row("J1…J6 deg", "  ".join(_num(v, 2) for v in joints))
    table.add_row("gripper", _gripper(state_pwm, gripper_us))
    table.add_row("arm", "—" if view.paused is None else ("PAUSED (p resumes)" if view.paused else "running"))
    jog = f"{view.moving} (joystick ±{view.joystick_value - 128})" if view.moving else "still"
    if view.busy:
        jog += f" · waiting: {view.busy}"
    table.add_row("jog", jog)
    table.add_row("level", f"{view.level}/{view.levels}: step {view.step_size}, F {view.speed}")
    if view.record_path:
        table.add_row("recording", f"{view.record_path} ({view.recorded} pose{'s' if view.recorded != 1 else ''})")
    return table


def _key_table(view: JogView, keymap: KeyMap) -> Table:
    table = Table.grid(padding=(0, 1))
    for _ in range(3):
        table.add_column(style="bold", justify="right", no_wrap=True)
        table.add_column(no_wrap=True)
    cells: list[str] = []
    for axis in _AXES[view.mode]:
        name = axis.upper()
        cells += [f"{_keys(keymap, axis + '_plus')}/{_keys(keymap, axis + '_minus')}", f"{name} +/−"]
    for action in _COMMON:
        cells += [_keys(keymap, action), ACTIONS[action][1]]
    cells += ["Ctrl-C", "quit (exit 130)"]
    for start in range(0, len(cells), 6):
        row = cells[start : start + 6]
        table.add_row(*row, *([""] * (6 - len(row))))
    return table


def render_jog(view: JogView, pose: Reported | None, pwm_us, keymap: KeyMap,
               gripper_us: tuple[float, float]) -> Panel:
    """The whole panel.  ``pose``: the reported pose (None until complete); ``pwm_us``: the
    reported PWM; ``gripper_us``: the profile's (open, close) values, to name the state."""
    kind = "step" if view.stepping else "continuous"
    title = f"armctl jog · {view.mode} mode · {kind} · level {view.level}/{view.levels}"
    parts = [_pose_table(view, pose, pwm_us, gripper_us)]
    if view.message:
        parts.append(Text(f"» {view.message}"))
    parts += [Text(""), Text(f"keys ({view.mode} mode)", style="bold"), _key_table(view, keymap)]
    subtitle = view.url or None
    return Panel(Group(*parts), title=title, subtitle=subtitle, expand=False)
