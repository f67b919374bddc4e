"""Which key does what: the default key map, and the one armctl.toml's ``[jog.keys]`` makes.

Strategy: one table of actions (``ACTIONS``: name → what it does, in which mode), a default
binding for each, and ``KeyMap.action(key, mode)`` — a plain dict lookup.  Jog actions name an
axis and a direction (``j1_plus`` … ``j6_minus`` in joint mode, ``x_plus`` … ``z_minus`` in
linear mode) and exist only in their mode, so one key may serve both modes; every other action
works in both.  ``[jog.keys]`` replaces the keys of the actions it names, as one key name or a
list (``quit = ["x", "esc"]``); an unknown action or key name, or one key bound to two actions
in the same mode, is a ``JogConfigError`` naming the file and the key.  Ctrl-C is not in the
table: it always quits (exit 130).  Pure.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from ..errors import ArmctlError
from ..core.protocol import JOYSTICK_LINEAR_AXIS

JOINT, LINEAR = "joint", "linear"
MODES = (JOINT, LINEAR)

NAMED_KEYS = frozenset({
    "space", "enter", "tab", "esc", "backspace", "up", "down", "left", "right", "pageup", "pagedown",
    "home", "end", "insert", "delete",
})


class JogConfigError(ArmctlError):
    """A ``[jog]`` table in armctl.toml that cannot be used (exit 2)."""


@dataclass(frozen=True)
class JogAxis:
    """A jog action: joystick ``axis`` (0…5 = J1…J6, 100 = linear) and, for the linear axis,
    which of X, Y, Z (``index``); ``sign`` +1 towards larger values, −1 towards smaller."""

    axis: int
    index: int
    sign: int
    label: str  # "J1+", "X−"

    @property
    def is_linear(self) -> bool:
        return self.axis == JOYSTICK_LINEAR_AXIS


def _jog_actions() -> dict[str, JogAxis]:
    actions = {}
    for joint in range(1, 7):
        actions[f"j{joint}_plus"] = JogAxis(joint - 1, 0, +1, f"J{joint}+")
        actions[f"j{joint}_minus"] = JogAxis(joint - 1, 0, -1, f"J{joint}−")
    for index, letter in enumerate("xyz"):
        actions[f"{letter}_plus"] = JogAxis(JOYSTICK_LINEAR_AXIS, index, +1, f"{letter.upper()}+")
        actions[f"{letter}_minus"] = JogAxis(JOYSTICK_LINEAR_AXIS, index, -1, f"{letter.upper()}−")
    return actions


JOG_ACTIONS = _jog_actions()

# action → (mode it works in or None for both, what the screen calls it)
ACTIONS: dict[str, tuple[str | None, str]] = {
    **{name: (LINEAR if jog.is_linear else JOINT, jog.label) for name, jog in JOG_ACTIONS.items()},
    "mode": (None, "joint ↔ linear"),
    "faster": (None, "speed level up"),
    "slower": (None, "speed level down"),
    "open": (None, "gripper open"),
    "close": (None, "gripper close"),
    "stop": (None, "stop now"),
    "pause": (None, "pause / resume"),
    "record": (None, "record pose"),
    "quit": (None, "quit"),
    "step": (None, "continuous ↔ step"),
}

DEFAULT_KEYS: dict[str, tuple[str, ...]] = {
    "j1_plus": ("q",), "j1_minus": ("a",),
    "j2_plus": ("w",), "j2_minus": ("s",),
    "j3_plus": ("e",), "j3_minus": ("d",),
    "j4_plus": ("r",), "j4_minus": ("f",),
    "j5_plus": ("t",), "j5_minus": ("g",),
    "j6_plus": ("y",), "j6_minus": ("h",),
    # +X is forward (away from the user facing the arm from behind), +Y to the left, +Z up.
    "x_plus": ("up",), "x_minus": ("down",),
    "y_plus": ("left",), "y_minus": ("right",),
    "z_plus": ("pageup",), "z_minus": ("pagedown",),
    "mode": ("m",),
    "faster": ("+", "="),
    "slower": ("-",),
    "open": ("o",),
    "close": ("c",),
    "stop": ("space",),
    "pause": ("p",),
    "record": ("enter",),
    "quit": ("x", "esc"),
    "step": ("tab",),
}


def valid_key_name(name: str) -> bool:
    """A single printable character (not a space) or one of the named keys."""
    return name in NAMED_KEYS or (len(name) == 1 and name.isprintable() and not name.isspace())


@dataclass(frozen=True)
class KeyMap:
    """action → keys; ``action(key, mode)`` looks a key up in one mode."""

    keys: Mapping[str, tuple[str, ...]]

    def __post_init__(self) -> None:
        lookup: dict[str, dict[str, str]] = {mode: {} for mode in MODES}
        for action, keys in self.keys.items():
            action_mode = ACTIONS[action][0]
            for mode in MODES:
                if action_mode not in (None, mode):
                    continue
                for key in keys:
                    other = lookup[mode].get(key)
                    if other is not None and other != action:
                        raise JogConfigError(f"key {key!r} is bound to both {other!r} and {action!r} in {mode} mode")
                    lookup[mode][key] = action
        object.__setattr__(self, "_lookup", lookup)

    def action(self, key: str, mode: str) -> str | None:
        return self._lookup[mode].get(key)  # type: ignore[attr-defined]

    def keys_for(self, action: str) -> tuple[str, ...]:
        return tuple(self.keys.get(action, ()))


def default_keymap() -> KeyMap:
    return KeyMap(dict(DEFAULT_KEYS))


def keymap_from_config(table: Mapping | None, source: str = "armctl.toml") -> KeyMap:
    """The default map with the actions ``[jog.keys]`` names rebound."""
    keys = dict(DEFAULT_KEYS)
    for action, value in (table or {}).items():
        where = f"{source}: jog.keys.{action}"
        if action not in ACTIONS:
            raise JogConfigError(f"{where}: unknown action (known: {', '.join(ACTIONS)})")
        names = (value,) if isinstance(value, str) else value
        if not isinstance(names, (list, tuple)) or not names or not all(isinstance(n, str) for n in names):
            raise JogConfigError(f"{where}: must be a key name or a list of key names, not {value!r}")
        for name in names:
            if not valid_key_name(name):
                raise JogConfigError(
                    f"{where}: {name!r} is not a key name (one character, or one of {', '.join(sorted(NAMED_KEYS))})"
                )
        keys[action] = tuple(names)
    try:
        return KeyMap(keys)
    except JogConfigError as error:
        raise JogConfigError(f"{source}: [jog.keys]: {error}") from None
