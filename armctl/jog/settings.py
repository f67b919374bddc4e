"""Jog's numbers: dead-man timings and speed levels, from armctl.toml's ``[jog]`` table.

Strategy: one frozen dataclass with the defaults, one function that checks a ``[jog]`` table
key by key (each value's unit is in its name) and returns a copy with the values it gives.  The
``[jog.keys]`` sub-table is keymap.py's.  Pure; a bad value is a ``JogConfigError`` naming the
file and the key.

Speed levels are parallel lists, one entry per level (at least three by default, any number
≥ 1 when configured, all lists the same length):

- ``joystick_offsets``: how far from the neutral 128 the joystick byte goes (21…127: the still
  band is 108…148, and PROTOCOL.md says further out = faster);
- ``step_mm`` / ``step_deg``: the step-jog increment in linear / joint mode;
- ``linear_speed_mm_min`` / ``joint_speed_deg_s``: F of step moves, gripper moves and taught lines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Mapping

from ..core.limits import REPEAT_DELAY_RANGE_MS
from ..host.profile import unknown_key_hint
from ..core.protocol import JOYSTICK_NEUTRAL, JOYSTICK_STILL_RANGE
from .keymap import JogConfigError, KeyMap, keymap_from_config

REPEAT_GAP_LIMIT_MS = 140.0  # the 150 ms bound, less the edge loop's wake-up slack


@dataclass(frozen=True)
class JogSettings:
    initial_delay_ms: float = 500.0  # a tap moves no longer than this (set ≥ your terminal's repeat delay)
    repeat_gap_ms: float = 100.0  # neutral when no repeat came for this long (≤ 140)
    refresh_ms: float = 0.0  # 0: never resend an unchanged joystick value (see docs/jog.md)
    escape_ms: float = 50.0  # a lone Esc is a key after this long
    joystick_offsets: tuple[int, ...] = (24, 60, 110)
    step_mm: tuple[float, ...] = (1.0, 5.0, 10.0)
    step_deg: tuple[float, ...] = (1.0, 5.0, 10.0)
    linear_speed_mm_min: tuple[float, ...] = (600.0, 1500.0, 3000.0)
    joint_speed_deg_s: tuple[float, ...] = (10.0, 30.0, 60.0)
    level: int = 1  # starting speed level, 1-based

    @property
    def levels(self) -> int:
        return len(self.joystick_offsets)


# level list → the range of each entry (joystick_offsets: see _offset_ok); a desktop arm's
# step is at most a few cm or a quarter turn, its speeds those of armctl's own F checks
_LEVEL_LISTS = {
    "joystick_offsets": (1.0, 255.0),  # then _offset_ok says exactly which are allowed
    "step_mm": (0.001, 100.0),
    "step_deg": (0.001, 90.0),
    "linear_speed_mm_min": (0.1, 60_000.0),
    "joint_speed_deg_s": (0.01, 1000.0),
}
_MS_RANGES = {
    "initial_delay_ms": REPEAT_DELAY_RANGE_MS,
    "repeat_gap_ms": (20.0, REPEAT_GAP_LIMIT_MS),
    "refresh_ms": (0.0, 10000.0),
    "escape_ms": (5.0, 1000.0),
}


def _bad(source: str, key: str, text: str) -> JogConfigError:
    return JogConfigError(f"{source}: jog.{key} {text}")


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)


def _offset_ok(value: float) -> bool:
    low, high = JOYSTICK_STILL_RANGE
    return value == int(value) and JOYSTICK_NEUTRAL + value > high and JOYSTICK_NEUTRAL - value < low and value <= 127


def jog_from_config(table: Mapping | None, source: str = "armctl.toml") -> tuple[JogSettings, KeyMap]:
    """A ``[jog]`` table read whole: its settings and its ``[jog.keys]`` (``JogConfigError`` naming
    ``source``).  ``armctl jog`` reads it so, and ``armctl config`` checks it so."""
    settings = settings_from_config(table, source)
    keys = (table or {}).get("keys", {})
    if not isinstance(keys, dict):
        raise JogConfigError(f"{source}: jog.keys must be a table ([jog.keys]), not {keys!r}")
    return settings, keymap_from_config(keys, source)


def settings_from_config(table: Mapping | None, source: str = "armctl.toml") -> JogSettings:
    """``JogSettings`` with the values of a ``[jog]`` table (its ``keys`` sub-table is skipped)."""
    values: dict = {}
    known = {f.name for f in fields(JogSettings)}
    for key, value in (table or {}).items():
        if key == "keys":
            continue
        if key not in known:
            raise _bad(source, key, f"is not a jog setting{unknown_key_hint(key, [*sorted(known), 'keys'])}")
        if key in _MS_RANGES:
            low, high = _MS_RANGES[key]
            number = _number(value)
            if number is None or not low <= number <= high:
                raise _bad(source, key, f"must be a number of milliseconds {low:g}…{high:g}, not {value!r}")
            values[key] = number
        elif key in _LEVEL_LISTS:
            low, high = _LEVEL_LISTS[key]
            if not isinstance(value, list) or not value or any(_number(v) is None or not low <= _number(v) <= high for v in value):
                raise _bad(source, key, f"must be a non-empty list of positive numbers {low:g}…{high:g}, not {value!r}")
            if key == "joystick_offsets" and not all(_offset_ok(float(v)) for v in value):
                raise _bad(source, key, f"entries must be whole numbers 21…127 (outside the still band), not {value!r}")
            values[key] = tuple(int(v) for v in value) if key == "joystick_offsets" else tuple(float(v) for v in value)
        elif key == "level":
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 1000:
                raise _bad(source, key, f"must be a whole number ≥ 1 (a speed level), not {value!r}")
            values[key] = value
    settings = replace(JogSettings(), **values)
    counts = {name: len(getattr(settings, name)) for name in _LEVEL_LISTS}
    if len(set(counts.values())) != 1:
        listed = ", ".join(f"{name} has {count}" for name, count in counts.items())
        raise JogConfigError(f"{source}: [jog] speed-level lists must have the same length ({listed})")
    if settings.level > settings.levels:
        raise _bad(source, "level", f"= {settings.level} but there are only {settings.levels} levels")
    return settings
