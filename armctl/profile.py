"""The arm profile: limits, speeds, link lengths and timing constants, read from TOML.

Strategy: one schema table (section → key → checker) drives everything.  A TOML document is
read with ``tomllib``, every key of it is checked against the schema (so an unknown key, a
wrong type or a min > max pair is reported with the file and the dotted key), the checked
values are laid over the packaged default (``armctl/data/default_profile.toml``) section by
section, and the result is built into frozen dataclasses and cross-checked (fixed poses inside
the joint limits, gripper values inside the PWM range).  Pure apart from reading files.

Where a profile comes from (``load_profile``): an explicit file (``--profile FILE``); else the
first ``armctl.toml`` found walking up from the working directory — its ``[profile]`` table, or
``profile = "path.toml"`` resolved relative to that armctl.toml; else the packaged default.
"""

from __future__ import annotations

import difflib
import functools
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Callable

from .errors import ProfileError
from .kinematics import JOINT_COUNT, Kinematics, Links

CONFIG_NAME = "armctl.toml"
DEFAULT_RESOURCE = ("armctl.data", "default_profile.toml")
GRIPPER_STATES = ("open", "closed")
FIXED_POSES = ("0", "1", "2", "3")


@dataclass(frozen=True)
class Workspace:
    """Safety box of the tool point in robot coordinates (mm) and its reach radius."""

    x_mm: tuple[float, float]
    y_mm: tuple[float, float]
    z_mm: tuple[float, float]
    reach_mm: float


@dataclass(frozen=True)
class Speeds:
    max_linear_mm_min: float
    max_joint_deg_s: float
    max_accel_mm_s2: float
    attitude_deg_s: float


@dataclass(frozen=True)
class Pwm:
    range_us: tuple[float, float]
    channels: tuple[int, ...]
    gripper_open_us: float
    gripper_close_us: float
    initial_us: float


@dataclass(frozen=True)
class Timing:
    joint_ramp_s: tuple[float, ...]  # smoothing levels 1…6
    command_overhead_s: float
    pwm_change_s: float
    pose_smoothing: int

    def ramp_s(self, smoothing: int) -> float:
        """Start/stop ramp of a joint move at smoothing level 0…6 (0 = none)."""
        return 0.0 if smoothing <= 0 else self.joint_ramp_s[min(smoothing, 6) - 1]


@dataclass(frozen=True)
class LintOptions:
    end_gripper: str | None = None  # "open" / "closed"
    end_paused: bool | None = None


@dataclass(frozen=True)
class Profile:
    name: str
    workspace: Workspace
    joint_limits_deg: tuple[tuple[float, float], ...]
    speed: Speeds
    pwm: Pwm
    poses: tuple[tuple[float, ...], ...]  # fixed poses 0…3 as joint angles
    links: Links
    timing: Timing
    lint: LintOptions
    source: str = field(default="", compare=False)  # where it was read from, for messages

    @functools.cached_property
    def kinematics(self) -> Kinematics:
        return Kinematics(self.links, self.joint_limits_deg, self.poses[0])


# --- the schema ---------------------------------------------------------------------------------


class _Bad(Exception):
    """A value's problem, completed with the file and key by the caller."""


def _number(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _Bad(f"must be a number, not {value!r}")
    return float(value)


def _positive(value) -> float:
    if (number := _number(value)) <= 0:
        raise _Bad(f"must be greater than 0, not {value!r}")
    return number


def _not_negative(value) -> float:
    if (number := _number(value)) < 0:
        raise _Bad(f"must not be negative, not {value!r}")
    return number


def _numbers(count: int, each: Callable = _number) -> Callable:
    def check(value) -> tuple:
        if not isinstance(value, list) or len(value) != count:
            raise _Bad(f"must be a list of {count} numbers, not {value!r}")
        return tuple(each(v) for v in value)

    return check


def _pair(value) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise _Bad(f"must be a [min, max] pair of numbers, not {value!r}")
    low, high = _number(value[0]), _number(value[1])
    if low > high:
        raise _Bad(f"has min {low:g} > max {high:g}")
    return low, high


def _channels(value) -> tuple[int, ...]:
    if (not isinstance(value, list) or not value or len(set(value)) != len(value)
            or any(isinstance(v, bool) or v not in (1, 2, 3, 4) for v in value)):
        raise _Bad(f"must be a non-empty list of distinct PWM channels 1…4, not {value!r}")
    return tuple(int(v) for v in value)


def _smoothing(value) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 6:
        raise _Bad(f"must be a whole number 0…6, not {value!r}")
    return value


def _text(value) -> str:
    if not isinstance(value, str):
        raise _Bad(f"must be a string, not {value!r}")
    return value


def _gripper_state(value) -> str:
    if value not in GRIPPER_STATES:
        raise _Bad(f"must be \"open\" or \"closed\", not {value!r}")
    return value


def _boolean(value) -> bool:
    if not isinstance(value, bool):
        raise _Bad(f"must be true or false, not {value!r}")
    return value


_SCHEMA: dict[str, Any] = {
    "name": _text,
    "workspace": {"x_mm": _pair, "y_mm": _pair, "z_mm": _pair, "reach_mm": _positive},
    "joints": {f"j{k}_deg": _pair for k in range(1, JOINT_COUNT + 1)},
    "speed": {
        "max_linear_mm_min": _positive, "max_joint_deg_s": _positive, "max_accel_mm_s2": _positive,
        "attitude_deg_s": _positive,
    },
    "pwm": {
        "range_us": _pair, "channels": _channels, "gripper_open_us": _number, "gripper_close_us": _number,
        "initial_us": _number,
    },
    "poses": {pose: _numbers(JOINT_COUNT) for pose in FIXED_POSES},
    "links": {
        "base_height_mm": _not_negative, "shoulder_offset_mm": _number, "upper_arm_mm": _positive,
        "elbow_offset_mm": _number, "forearm_mm": _positive, "tool_mm": _not_negative,
    },
    "timing": {
        "joint_ramp_s": _numbers(6, _not_negative), "command_overhead_s": _not_negative,
        "pwm_change_s": _not_negative, "pose_smoothing": _smoothing,
    },
    "lint": {"end_gripper": _gripper_state, "end_paused": _boolean},
}
_OPTIONAL_SECTIONS = {"lint"}


def _unknown(source: str, key: str, known) -> ProfileError:
    close = difflib.get_close_matches(key.rsplit(".", 1)[-1], list(known), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else f" (known: {', '.join(known)})"
    return ProfileError(f"{source}: unknown key {key!r}{hint}")


def _check(data: dict, source: str, prefix: str = "") -> dict:
    """``data`` with every value checked and converted; raises ProfileError naming the key."""
    checked: dict[str, Any] = {}
    for section, content in data.items():
        rule = _SCHEMA.get(section)
        if rule is None:
            raise _unknown(source, prefix + section, _SCHEMA)
        if not isinstance(rule, dict):
            checked[section] = _apply(rule, content, source, prefix + section)
            continue
        if not isinstance(content, dict):
            raise ProfileError(f"{source}: {prefix}{section} must be a table ([{section}]), not {content!r}")
        checked[section] = {}
        for key, value in content.items():
            if key not in rule:
                raise _unknown(source, f"{prefix}{section}.{key}", rule)
            checked[section][key] = _apply(rule[key], value, source, f"{prefix}{section}.{key}")
    return checked


def _apply(rule: Callable, value, source: str, key: str):
    try:
        return rule(value)
    except _Bad as bad:
        raise ProfileError(f"{source}: {key} {bad}") from None


# --- building -----------------------------------------------------------------------------------


def _merge(base: dict, layer: dict) -> dict:
    merged = {k: dict(v) if isinstance(v, dict) else v for k, v in base.items()}
    for key, value in layer.items():
        if isinstance(value, dict):
            merged.setdefault(key, {}).update(value)
        else:
            merged[key] = value
    return merged


def _build(data: dict, source: str, prefix: str) -> Profile:
    for section in _SCHEMA:
        if isinstance(_SCHEMA[section], dict) and section not in _OPTIONAL_SECTIONS:
            missing = [k for k in _SCHEMA[section] if k not in data.get(section, {})]
            if missing:
                raise ProfileError(f"{source}: {prefix}{section}.{missing[0]} is missing")
    joints = data["joints"]
    profile = Profile(
        name=data.get("name", ""),
        workspace=Workspace(**data["workspace"]),
        joint_limits_deg=tuple(joints[f"j{k}_deg"] for k in range(1, JOINT_COUNT + 1)),
        speed=Speeds(**data["speed"]),
        pwm=Pwm(**data["pwm"]),
        poses=tuple(data["poses"][pose] for pose in FIXED_POSES),
        links=Links(**data["links"]),
        timing=Timing(**data["timing"]),
        lint=LintOptions(**data.get("lint", {})),
        source=source,
    )
    _cross_check(profile, source, prefix)
    return profile


def _cross_check(profile: Profile, source: str, prefix: str) -> None:
    low, high = profile.pwm.range_us
    if low < 500 or high > 2500:
        raise ProfileError(f"{source}: {prefix}pwm.range_us {low:g}…{high:g} leaves the protocol's 500…2500 µs")
    for key in ("gripper_open_us", "gripper_close_us", "initial_us"):
        value = getattr(profile.pwm, key)
        if not low <= value <= high:
            raise ProfileError(f"{source}: {prefix}pwm.{key} = {value:g} is outside pwm.range_us {low:g}…{high:g}")
    for number, pose in enumerate(profile.poses):
        for k, (angle, (j_low, j_high)) in enumerate(zip(pose, profile.joint_limits_deg)):
            if not j_low <= angle <= j_high:
                raise ProfileError(
                    f"{source}: {prefix}poses.{number} has J{k + 1} = {angle:g}, outside joints.j{k + 1}_deg"
                    f" {j_low:g}…{j_high:g}"
                )


@functools.lru_cache(maxsize=1)
def _default_data() -> dict:
    package, name = DEFAULT_RESOURCE
    text = resources.files(package).joinpath(name).read_bytes()
    source = f"<packaged {name}>"
    return _check(_parse(text, source), source)


def parse_profile(data: dict, source: str = "<profile>", prefix: str = "") -> Profile:
    """A profile from a TOML-shaped dict laid over the packaged default.

    ``prefix`` is prepended to key names in messages (``"profile."`` for an armctl.toml table).
    """
    return _build(_merge(_default_data(), _check(data, source, prefix)), source, prefix)


@functools.lru_cache(maxsize=1)
def default_profile() -> Profile:
    """The packaged default profile (every number illustrative)."""
    package, name = DEFAULT_RESOURCE
    return _build(_default_data(), f"<packaged {name}>", "")


# --- files ------------------------------------------------------------------------------------


def _parse(data: bytes, source: str) -> dict:
    try:
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as error:
        raise ProfileError(f"{source}: not UTF-8 text (byte {error.start})") from None
    except tomllib.TOMLDecodeError as error:
        raise ProfileError(f"{source}: invalid TOML: {error}") from None


def read_toml(path: Path) -> dict:
    """A TOML file as a dict; every failure is a ProfileError naming the file."""
    from .inputs import MAX_TOML_BYTES, InputTooLarge, read_file_bounded

    try:
        data = read_file_bounded(str(path), str(path), MAX_TOML_BYTES)  # /dev/zero is not a profile
    except FileNotFoundError:
        raise ProfileError(f"{path}: file not found") from None
    except OSError as error:
        raise ProfileError(f"{path}: cannot read: {error.strerror or error}") from None
    except InputTooLarge as error:
        raise ProfileError(str(error)) from None
    return _parse(data, str(path))


def find_config(start: Path | None = None) -> tuple[Path | None, dict]:
    """The first armctl.toml in ``start`` (default: the working directory) or a parent, and
    its whole content; ``(None, {})`` when there is none."""
    directory = Path.cwd() if start is None else Path(start)
    directory = directory.resolve()
    for candidate in (directory, *directory.parents):
        path = candidate / CONFIG_NAME
        if path.is_file():
            return path, read_toml(path)
    return None, {}


def load_profile(path: Path | str | None = None, start: Path | None = None) -> Profile:
    """The profile to use: ``path`` if given, else the one an armctl.toml names, else the default."""
    if path is not None:
        return parse_profile(read_toml(Path(path)), str(path))
    config_path, config = find_config(start)
    if config_path is None or "profile" not in config:
        return default_profile()
    entry = config["profile"]
    if isinstance(entry, dict):
        return parse_profile(entry, str(config_path), prefix="profile.")
    if isinstance(entry, str):
        target = config_path.parent / entry
        return parse_profile(read_toml(target), str(target))
    raise ProfileError(
        f"{config_path}: profile must be a table ([profile]) or a path string, not {entry!r}"
    )
