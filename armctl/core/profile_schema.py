"""The arm profile's schema: section → key → checker, and the checking of TOML-shaped data against it.

Strategy: one table, ``PROFILE_SCHEMA``, drives everything: ``check_profile_data`` walks a
document against it, so an unknown key, a wrong type, NaN/inf, a value outside its physically
sensible range or a min > max pair is a ProfileError naming the source and the dotted key.  A
checker raises ``BadValue`` with the value's problem; the caller adds the file and key (armctl.toml's
top level, armctl/host/config_file.py, words its own errors the same way).  No I/O.
"""

from __future__ import annotations

import math
from typing import Any, Callable

from ..errors import ProfileError
from .kinematics import JOINT_COUNT
from .limits import FIFO_RANGE_FRAMES, SPEED_FACTOR_RANGE, STATUS_JITTER_RANGE_MS
from .profile_model import CONTROL_FRAMES, FIXED_POSES, GRIPPER_STATES, SPEED_TOLERANCE_RANGE, STATUS_XYZ_FRAMES
from .protocol import PWM_RANGE_US
from .toml_reading import short_repr

class BadValue(Exception):
    """A value's problem, completed with the file and key by the caller."""


def _number(value) -> float:
    try:  # a whole number too large for a float (a dict given to parse_profile) is not one either
        number = None if isinstance(value, bool) or not isinstance(value, (int, float)) else float(value)
    except OverflowError:
        number = None
    if number is None or not math.isfinite(number):
        raise BadValue(f"must be a number, not {short_repr(value)}")
    return number


def _in(low: float, high: float) -> Callable:
    """A finite number from ``low`` to ``high``: a physically sensible range for a desktop arm,
    and one the motion model computes with without dividing by zero or overflowing."""

    def check(value) -> float:
        number = _number(value)
        if not low <= number <= high:
            raise BadValue(f"must be from {low:g} to {high:g}, not {short_repr(value)}")
        return number

    return check


def _numbers(count: int, each: Callable = _number) -> Callable:
    def check(value) -> tuple:
        if not isinstance(value, list) or len(value) != count:
            raise BadValue(f"must be a list of {count} numbers, not {short_repr(value)}")
        return tuple(each(v) for v in value)

    return check


def _pair(low: float, high: float) -> Callable:
    each = _in(low, high)

    def check(value) -> tuple[float, float]:
        if not isinstance(value, list) or len(value) != 2:
            raise BadValue(f"must be a [min, max] pair of numbers, not {short_repr(value)}")
        first, second = each(value[0]), each(value[1])
        if first > second:
            raise BadValue(f"has min {first:g} > max {second:g}")
        return first, second

    return check


def _channels(value) -> tuple[int, ...]:
    if (not isinstance(value, list) or not value
            or any(isinstance(v, bool) or not isinstance(v, int) or v not in (1, 2, 3, 4) for v in value)
            or len(set(value)) != len(value)):
        raise BadValue(f"must be a non-empty list of distinct PWM channels 1…4, not {short_repr(value)}")
    return tuple(int(v) for v in value)


def _smoothing(value) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 6:
        raise BadValue(f"must be a whole number 0…6, not {short_repr(value)}")
    return value


def _text(value) -> str:
    if not isinstance(value, str):
        raise BadValue(f"must be a string, not {short_repr(value)}")
    return value


def _gripper_state(value) -> str:
    if value not in GRIPPER_STATES:
        raise BadValue(f"must be \"open\" or \"closed\", not {short_repr(value)}")
    return value


def _boolean(value) -> bool:
    if not isinstance(value, bool):
        raise BadValue(f"must be true or false, not {short_repr(value)}")
    return value


def _one_of(choices: tuple[str, ...]) -> Callable:
    def check(value) -> str:
        if value not in choices:
            raise BadValue(f"must be {' or '.join(repr(c).replace(chr(39), chr(34)) for c in choices)}, not {short_repr(value)}")
        return value

    return check


def _whole_in(low: int, high: int) -> Callable:
    def check(value) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise BadValue(f"must be a whole number {low}…{high}, not {short_repr(value)}")
        return value

    return check


# Ranges: a desktop arm reaches well under 10 m, turns a joint at most two full turns
# either way, moves at most 100 m/min; a timing constant is at most a minute.  Lengths and
# speeds that the motion model divides by have a lower bound well above underflow.
_MM = _in(-10_000.0, 10_000.0)
_DEG = _in(-720.0, 720.0)
_PWM_US = _in(*PWM_RANGE_US)
MIN_TIME_S = 1e-6  # a timing constant is 0 or at least this: a shorter one makes speeds overflow


def _seconds(value) -> float:
    number = _in(0.0, 60.0)(value)
    if 0.0 < number < MIN_TIME_S:
        raise BadValue(f"must be 0 or from {MIN_TIME_S:g} to 60, not {short_repr(value)}")
    return number


_LINK_MM = _in(1.0, 10_000.0)
_MM_PAIR = _pair(-10_000.0, 10_000.0)

PROFILE_SCHEMA: dict[str, Any] = {
    "name": _text,
    "workspace": {"x_mm": _MM_PAIR, "y_mm": _MM_PAIR, "z_mm": _MM_PAIR, "reach_mm": _LINK_MM},
    "joints": {f"j{k}_deg": _pair(-720.0, 720.0) for k in range(1, JOINT_COUNT + 1)},
    "speed": {
        "max_linear_mm_min": _in(1.0, 100_000.0), "max_joint_deg_s": _in(0.1, 3600.0),
        "max_accel_mm_s2": _in(1.0, 100_000.0), "attitude_deg_s": _in(0.1, 3600.0),
        "default_linear_mm_min": _in(1.0, 100_000.0), "default_joint_deg_s": _in(0.1, 3600.0),
    },
    "pwm": {
        "range_us": _pair(*PWM_RANGE_US), "channels": _channels, "gripper_open_us": _PWM_US,
        "gripper_close_us": _PWM_US, "initial_us": _PWM_US,
    },
    "poses": {pose: _numbers(JOINT_COUNT, _DEG) for pose in FIXED_POSES},
    "links": {
        "base_height_mm": _in(0.0, 10_000.0), "shoulder_offset_mm": _MM, "upper_arm_mm": _LINK_MM,
        "elbow_offset_mm": _MM, "forearm_mm": _LINK_MM, "tool_mm": _in(0.0, 10_000.0),
    },
    "timing": {
        "joint_ramp_s": _numbers(6, _seconds), "command_overhead_s": _seconds,
        "pwm_change_s": _seconds, "pose_smoothing": _smoothing,
    },
    "lint": {"end_gripper": _gripper_state, "end_paused": _boolean},
    "connector": {
        "fifo_frames": _whole_in(*FIFO_RANGE_FRAMES), "control_frames": _one_of(CONTROL_FRAMES),
        "status_xyz_frame": _one_of(STATUS_XYZ_FRAMES), "speed_factor": _in(*SPEED_FACTOR_RANGE),
        "kinematics_verified": _boolean, "speed_tolerance": _in(*SPEED_TOLERANCE_RANGE),
        "status_jitter_ms": _in(*STATUS_JITTER_RANGE_MS),
    },
}
_OPTIONAL_SECTIONS = {"lint"}


def unknown_key_hint(key: str, known) -> str:
    """`` (did you mean 'port'?)`` for a misspelt key, else the list of known keys: the one
    wording of every unknown key in armctl.toml and a profile."""
    import difflib  # only when a key is unknown

    close = difflib.get_close_matches(key.rsplit(".", 1)[-1], list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else f" (known: {', '.join(known)})"


def _unknown(source: str, key: str, known) -> ProfileError:
    return ProfileError(f"{source}: unknown key {key!r}{unknown_key_hint(key, known)}")


def check_profile_data(data: dict, source: str, prefix: str = "") -> dict:
    """``data`` with every value checked and converted; raises ProfileError naming the key."""
    checked: dict[str, Any] = {}
    for section, content in data.items():
        rule = PROFILE_SCHEMA.get(section)
        if rule is None:
            raise _unknown(source, prefix + section, PROFILE_SCHEMA)
        if not isinstance(rule, dict):
            checked[section] = _apply(rule, content, source, prefix + section)
            continue
        if not isinstance(content, dict):
            raise ProfileError(f"{source}: {prefix}{section} must be a table ([{section}]), not {short_repr(content)}")
        checked[section] = {}
        for key, value in content.items():
            if key not in rule:
                raise _unknown(source, f"{prefix}{section}.{key}", rule)
            checked[section][key] = _apply(rule[key], value, source, f"{prefix}{section}.{key}")
    return checked


def _apply(rule: Callable, value, source: str, key: str):
    try:
        return rule(value)
    except BadValue as bad:
        raise ProfileError(f"{source}: {key} {bad}") from None
