"""The arm profile: limits, speeds, link lengths and timing constants, read from TOML.

Strategy: one schema table (section → key → checker) drives everything.  A TOML document is
read with ``tomllib``, every key of it is checked against the schema (so an unknown key, a
wrong type, NaN/inf, a value outside its physically sensible range or a min > max pair is
reported with the file and the dotted key), the checked
values are laid over the packaged default (``armctl/data/default_profile.toml``) section by
section, and the result is built into frozen dataclasses and cross-checked (fixed poses inside
the joint limits, gripper values inside the PWM range).  Pure apart from reading files.

Where a profile comes from (``load_profile``): an explicit file (``--profile FILE``); else the
first ``armctl.toml`` found walking up from the working directory, else the user's armctl.toml
(``load_config``) — its ``[profile]`` table, or ``profile = "path.toml"`` resolved relative to
that armctl.toml; else the packaged default.

Provenance: every key knows where its number came from (``Profile.source_of``): the packaged
default's numbers are ``ILLUSTRATIVE`` guesses about a generic arm, except the few that are the
protocol's own ranges (``PROTOCOL_KEYS``); a key the user's profile file or armctl.toml gives
is named by that file; a measured value (a probe, later) is ``PROBE``.  Lint turns a finding
that rests on an illustrative number into a warning that says so (armctl/lint/engine.py).

The ``[connector]`` table holds what the vendor document leaves open about the arm's connector
and status (``Connector``: ``fifo_frames``, ``control_frames``, ``status_xyz_frame``,
``speed_factor``, ``kinematics_verified``).  Its packaged values are the document's reading (the
H-decisions, README), so their source is ``DOCUMENT``, not a guess; ``Connector.is_default(key)``
says whether a value is still that default (``armctl probe`` replaces them with measured ones).
The table may sit in a profile file, in armctl.toml's ``[profile]`` table, and at the top level
of armctl.toml (``[connector]``).  What is in effect is the arm's on the port (``arm_connector``):
the profile's own table, then what ``armctl probe`` kept with that arm (armctl/calibration.py),
then armctl.toml's top-level table if it names no arm or its ``measured_on`` is that arm.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import pkgutil
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from .errors import ConfigError, ProfileError
from .kinematics import JOINT_COUNT, Kinematics, Links
from .limits import BAUD_RANGE, FIFO_RANGE_FRAMES, SPEED_FACTOR_RANGE
from .protocol import PWM_RANGE_US

CONFIG_NAME = "armctl.toml"
DEFAULT_RESOURCE = ("armctl.data", "default_profile.toml")
GRIPPER_STATES = ("open", "closed")
FIXED_POSES = ("0", "1", "2", "3")

# Where a profile's number came from (Profile.source_of); a user's file is named by its path.
ILLUSTRATIVE = "illustrative"  # the packaged default's guess: nobody measured it
PROTOCOL = "protocol"  # a range the protocol itself fixes (PROTOCOL.md), true for every arm
PROBE = "probe"  # measured on the arm
DOCUMENT = "document"  # a [connector] default: the vendor document's reading (an H-decision)
MEASURED_ON = "measured_on"  # armctl.toml's [connector]: the arm its values belong to (armctl probe --write)
# Keys of the packaged default that are the protocol's own ranges, not guesses about an arm.
PROTOCOL_KEYS = frozenset({"pwm.range_us", "pwm.channels", "speed.max_accel_mm_s2"})


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
    # the speed of a move that gives none (``Arm.move``, ``armctl move``/``home``): a value
    # the profile defines, so sending it keeps the rule "never send a value nobody wrote"
    default_linear_mm_min: float = 3000.0
    default_joint_deg_s: float = 30.0


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


# [connector] speed_tolerance: 1 (the arm exactly as its speed_factor says) … 4 (as SPEED_FACTOR_RANGE:
# an arm further off has the wrong speed_factor, not a tolerance).
SPEED_TOLERANCE_RANGE = (1.0, 4.0)
CONTROL_FRAMES = ("queued", "arrival")  # H5, or its alternative
STATUS_XYZ_FRAMES = ("worktable", "robot")  # what status kind 0 reports after G54


@dataclass(frozen=True)
class Connector:
    """The arm's connector and status as they are, where the document leaves them open.

    ``fifo_frames``: frames the connector accepts behind the frame the arm is executing.  The
    document says 200; H6's two readings (the executing frame keeps its slot, or frees it) differ
    only in this sum, the one number a host can observe, so it is one setting.
    ``control_frames``: ``"queued"`` (H5: control frames wait in the FIFO behind motion) or
    ``"arrival"`` (they act the moment they land).  ``status_xyz_frame``: ``"worktable"`` (status
    kind 0 reports X/Y/Z in the frame G54 set) or ``"robot"``.  ``speed_factor``: the arm's real
    motion time ÷ the model's (``MotionModel`` applies it, once, for every reader).
    ``kinematics_verified``: the profile's links were checked against this arm; while false,
    forward and inverse kinematics never decide what the arm consumed or where it starts.
    ``speed_tolerance`` (≥ 1): how far the arm may stray from ``speed_factor``, either way — the
    streamer's time bound confirms a frame once an arm that many times slower (plus
    ``speed_tolerance − 1`` × 20 ms of handling) has finished it, and a sign of loss needs the arm
    that many times faster.  The document pins nothing: 2.0; ``armctl probe`` measures it."""

    fifo_frames: int
    control_frames: str
    status_xyz_frame: str
    speed_factor: float
    kinematics_verified: bool
    speed_tolerance: float = 2.0
    given: frozenset = field(default=frozenset(), compare=False)  # keys a file set (not the document's)

    def is_default(self, key: str) -> bool:
        """Whether ``key`` still has the document's default (no profile, armctl.toml or probe set it)."""
        if key not in CONNECTOR_KEYS:
            raise KeyError(key)
        return key not in self.given

    def fifo_proven(self, port_fifo_frames: int | None = None) -> bool:
        """Whether the connector is known to hold at least ``fifo_frames``: the value was measured
        or set (armctl.toml, a profile file, ``armctl probe --write``), or the port says its own
        FIFO (``port_fifo_frames``: a simulator's option) is at least that.  Otherwise a frame the
        arm dropped looks, to time alone, the same as one it ran."""
        if not self.is_default("fifo_frames"):
            return True
        return port_fifo_frames is not None and port_fifo_frames >= self.fifo_frames

    @property
    def control_on_arrival(self) -> bool:
        return self.control_frames == "arrival"

    @property
    def reports_robot_xyz(self) -> bool:
        return self.status_xyz_frame == "robot"


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
    connector: Connector
    source: str = field(default="", compare=False)  # where it was read from, for messages
    # "section.key" → ILLUSTRATIVE, PROTOCOL, PROBE or the file that gave it; see source_of
    sources: dict[str, str] = field(default_factory=dict, compare=False, repr=False)

    def source_of(self, key: str) -> str:
        """Where the number at ``key`` ("section.key") came from; a key without a recorded
        source (a profile built in code) counts as given by its builder."""
        return self.sources.get(key, "given")

    def illustrative(self, keys) -> list[str]:
        """Those of ``keys`` — "section.key", or a whole "section" — whose numbers (any of the
        section's) are the packaged default's illustrative guesses."""
        found = []
        for key in keys:
            if "." in key:
                unmeasured = self.source_of(key) == ILLUSTRATIVE
            else:
                unmeasured = any(k.startswith(key + ".") and v == ILLUSTRATIVE for k, v in self.sources.items())
            if unmeasured:
                found.append(key)
        return found

    @functools.cached_property
    def kinematics(self) -> Kinematics:
        return Kinematics(self.links, self.joint_limits_deg, self.poses[0])


# --- the schema ---------------------------------------------------------------------------------


class _Bad(Exception):
    """A value's problem, completed with the file and key by the caller."""


def _number(value) -> float:
    try:  # a whole number too large for a float (a dict given to parse_profile) is not one either
        number = None if isinstance(value, bool) or not isinstance(value, (int, float)) else float(value)
    except OverflowError:
        number = None
    if number is None or not math.isfinite(number):
        raise _Bad(f"must be a number, not {_short_repr(value)}")
    return number


def _in(low: float, high: float) -> Callable:
    """A finite number from ``low`` to ``high``: a physically sensible range for a desktop arm,
    and one the motion model computes with without dividing by zero or overflowing."""

    def check(value) -> float:
        number = _number(value)
        if not low <= number <= high:
            raise _Bad(f"must be from {low:g} to {high:g}, not {_short_repr(value)}")
        return number

    return check


def _numbers(count: int, each: Callable = _number) -> Callable:
    def check(value) -> tuple:
        if not isinstance(value, list) or len(value) != count:
            raise _Bad(f"must be a list of {count} numbers, not {_short_repr(value)}")
        return tuple(each(v) for v in value)

    return check


def _pair(low: float, high: float) -> Callable:
    each = _in(low, high)

    def check(value) -> tuple[float, float]:
        if not isinstance(value, list) or len(value) != 2:
            raise _Bad(f"must be a [min, max] pair of numbers, not {_short_repr(value)}")
        first, second = each(value[0]), each(value[1])
        if first > second:
            raise _Bad(f"has min {first:g} > max {second:g}")
        return first, second

    return check


def _channels(value) -> tuple[int, ...]:
    if (not isinstance(value, list) or not value
            or any(isinstance(v, bool) or not isinstance(v, int) or v not in (1, 2, 3, 4) for v in value)
            or len(set(value)) != len(value)):
        raise _Bad(f"must be a non-empty list of distinct PWM channels 1…4, not {_short_repr(value)}")
    return tuple(int(v) for v in value)


def _smoothing(value) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 6:
        raise _Bad(f"must be a whole number 0…6, not {_short_repr(value)}")
    return value


def _text(value) -> str:
    if not isinstance(value, str):
        raise _Bad(f"must be a string, not {_short_repr(value)}")
    return value


def _gripper_state(value) -> str:
    if value not in GRIPPER_STATES:
        raise _Bad(f"must be \"open\" or \"closed\", not {_short_repr(value)}")
    return value


def _boolean(value) -> bool:
    if not isinstance(value, bool):
        raise _Bad(f"must be true or false, not {_short_repr(value)}")
    return value


def _one_of(choices: tuple[str, ...]) -> Callable:
    def check(value) -> str:
        if value not in choices:
            raise _Bad(f"must be {' or '.join(repr(c).replace(chr(39), chr(34)) for c in choices)}, not {_short_repr(value)}")
        return value

    return check


def _whole_in(low: int, high: int) -> Callable:
    def check(value) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise _Bad(f"must be a whole number {low}…{high}, not {_short_repr(value)}")
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
        raise _Bad(f"must be 0 or from {MIN_TIME_S:g} to 60, not {_short_repr(value)}")
    return number


_LINK_MM = _in(1.0, 10_000.0)
_MM_PAIR = _pair(-10_000.0, 10_000.0)

_SCHEMA: dict[str, Any] = {
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
    },
}
_OPTIONAL_SECTIONS = {"lint"}
CONNECTOR_KEYS = tuple(_SCHEMA["connector"])


def unknown_key_hint(key: str, known) -> str:
    """`` (did you mean 'port'?)`` for a misspelt key, else the list of known keys: the one
    wording of every unknown key in armctl.toml and a profile."""
    import difflib  # only when a key is unknown

    close = difflib.get_close_matches(key.rsplit(".", 1)[-1], list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else f" (known: {', '.join(known)})"


def _unknown(source: str, key: str, known) -> ProfileError:
    return ProfileError(f"{source}: unknown key {key!r}{unknown_key_hint(key, known)}")


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
            raise ProfileError(f"{source}: {prefix}{section} must be a table ([{section}]), not {_short_repr(content)}")
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


def _sources(given: dict, source: str) -> dict[str, str]:
    """Every schema key's source: ``source`` for the keys ``given`` (checked user data), the
    packaged default's (PROTOCOL or ILLUSTRATIVE) for the rest."""
    sources = {}
    for section, rule in _SCHEMA.items():
        for key in ([f"{section}.{k}" for k in rule] if isinstance(rule, dict) else [section]):
            sources[key] = DOCUMENT if section == "connector" else PROTOCOL if key in PROTOCOL_KEYS else ILLUSTRATIVE
    for section, content in given.items():
        for key in ([f"{section}.{k}" for k in content] if isinstance(content, dict) else [section]):
            sources[key] = source
    return sources


def _build(data: dict, source: str, prefix: str, sources: dict[str, str]) -> Profile:
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
        connector=_connector(data["connector"], sources),
        source=source,
        sources=sources,
    )
    _cross_check(profile, source, prefix)
    return profile


def _connector(values: dict, sources: dict[str, str]) -> Connector:
    given = frozenset(k for k in CONNECTOR_KEYS if sources.get(f"connector.{k}", DOCUMENT) != DOCUMENT)
    return Connector(**values, given=given)


def with_connector(profile: Profile, table: dict, source: str) -> Profile:
    """``profile`` with armctl.toml's top-level ``[connector]`` ``table`` laid over its own, key by
    key (checked here; errors name ``source`` and ``connector.KEY``)."""
    given = _check({"connector": table}, source)["connector"]
    if not given:
        return profile
    sources = {**profile.sources, **{f"connector.{key}": source for key in given}}
    values = {key: getattr(profile.connector, key) for key in CONNECTOR_KEYS} | given
    return dataclasses.replace(profile, connector=_connector(values, sources), sources=sources)


def _cross_check(profile: Profile, source: str, prefix: str) -> None:
    low, high = profile.pwm.range_us  # inside the protocol's range: the schema checked it
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
    # pkgutil, not importlib.resources: the same bytes from a folder or a zip, without importing
    # tempfile, shutil and the compression modules at every start (issue 13: start-up)
    text = pkgutil.get_data(package, name)
    source = f"<packaged {name}>"
    return _check(_parse(text, source), source)


def parse_profile(data: dict, source: str = "<profile>", prefix: str = "") -> Profile:
    """A profile from a TOML-shaped dict laid over the packaged default.

    ``prefix`` is prepended to key names in messages (``"profile."`` for an armctl.toml table).
    """
    given = _check(data, source, prefix)
    return _build(_merge(_default_data(), given), source, prefix, _sources(given, source))


@functools.lru_cache(maxsize=1)
def default_profile() -> Profile:
    """The packaged default profile (every number illustrative)."""
    package, name = DEFAULT_RESOURCE
    return _build(_default_data(), f"<packaged {name}>", "", _sources({}, ""))


# --- files ------------------------------------------------------------------------------------


# TOML's own integer range (the spec: a whole number that is not a signed 64-bit one is an error);
# tomllib reads any length, and a 400-digit number overflows every float a check compares it with.
TOML_INT_RANGE = (-(2**63), 2**63 - 1)
MAX_TOML_DEPTH = 32  # tables and arrays nested deeper than this: no armctl setting is, and a check would recurse


def _parse(data: bytes, source: str) -> dict:
    """One TOML document as a dict; every failure (not UTF-8, invalid TOML, a whole number outside
    TOML's 64 bits, arrays or tables nested deeper than ``MAX_TOML_DEPTH``) is a ProfileError naming
    ``source``.  A UTF-8 byte-order mark is dropped, as a script's is."""
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as error:
        raise ProfileError(f"{source}: not UTF-8 text (byte {error.start})") from None
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProfileError(f"{source}: invalid TOML: {error}") from None
    except RecursionError:
        raise ProfileError(f"{source}: invalid TOML: arrays or tables nested more than {MAX_TOML_DEPTH} deep") from None
    except ValueError:  # int() past sys.get_int_max_str_digits(): thousands of digits
        raise ProfileError(f"{source}: invalid TOML: a whole number outside {TOML_INT_RANGE[0]}…{TOML_INT_RANGE[1]}") from None
    _check_toml_values(parsed, source)
    return parsed


def _check_toml_values(document: dict, source: str) -> None:
    """ProfileError naming the dotted key of the first whole number outside ``TOML_INT_RANGE`` or
    the first value nested deeper than ``MAX_TOML_DEPTH`` (iterative: no recursion to run out of)."""
    low, high = TOML_INT_RANGE
    pending: list[tuple[str, Any, int]] = [("", document, 0)]
    while pending:
        key, value, depth = pending.pop()
        if depth > MAX_TOML_DEPTH:
            raise ProfileError(f"{source}: {key} is nested more than {MAX_TOML_DEPTH} deep")
        if isinstance(value, dict):
            pending.extend((f"{key}.{k}" if key else k, v, depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            pending.extend((f"{key}[{i}]", v, depth + 1) for i, v in enumerate(value))
        elif isinstance(value, int) and not isinstance(value, bool) and not low <= value <= high:
            raise ProfileError(f"{source}: {key} = {_short_repr(value)} is outside TOML's whole numbers {low}…{high}")


def read_toml(path: Path) -> dict:
    """A TOML file as a dict; every failure is a ProfileError naming the file."""
    from .inputs import MAX_TOML_BYTES, UnusableInput, read_file_bounded

    try:
        data = read_file_bounded(str(path), str(path), MAX_TOML_BYTES)  # /dev/zero is not a profile
    except FileNotFoundError:
        raise ProfileError(f"{path}: file not found") from None
    except OSError as error:
        raise ProfileError(f"{path}: cannot read: {error.strerror or error}") from None
    except UnusableInput as error:  # too long, or a named pipe, device or directory
        raise ProfileError(str(error)) from None
    return _parse(data, str(path))


def read_config(path: Path) -> dict:
    """An armctl.toml's whole content with every top-level key checked: the one reading of a
    project file and of the user file."""
    data = read_toml(path)
    for key, value in data.items():
        check_config_value(path, key, value)
    return data


def find_config(start: Path | None = None) -> tuple[Path | None, dict]:
    """The first armctl.toml in ``start`` (default: the working directory) or a parent, and
    its whole content with every top-level key checked; ``(None, {})`` when there is none."""
    directory = Path.cwd() if start is None else Path(start)
    directory = directory.resolve()
    for candidate in (directory, *directory.parents):
        path = candidate / CONFIG_NAME
        if path.is_file():
            return path, read_config(path)
    return None, {}


def user_config_path() -> Path:
    """The user's armctl.toml: ``$XDG_CONFIG_HOME/armctl/armctl.toml`` (``~/.config/…`` when
    unset) on Linux and the BSDs, platformdirs' equivalent on macOS and Windows."""
    from .folders import user_folder

    return user_folder("config") / CONFIG_NAME


@dataclass(frozen=True)
class Config:
    """The effective top-level settings and the file each came from.

    Layering (README: Configuration): the nearest project armctl.toml wins key by key over the
    user file, at the top level — ``port``, ``baud``, ``profile``, ``[lint]`` and ``[jog]`` each
    come whole from one file, because a table's keys are checked together (the jog lists must
    have one length; a profile describes one arm) and an error names one file."""

    values: dict
    origins: dict[str, Path]
    project_path: Path | None
    user_path: Path

    def path_of(self, key: str) -> Path | None:
        """The file ``key`` came from (None: no file sets it)."""
        return self.origins.get(key)


def load_config(start: Path | None = None) -> Config:
    """The project file (``find_config``) laid over the user file, both read by ``read_config``."""
    project_path, project = find_config(start)
    user_path = user_config_path()
    user = read_config(user_path) if user_path.is_file() else {}
    origins = {key: user_path for key in user}
    origins.update({key: project_path for key in project})
    return Config({**user, **project}, origins, project_path, user_path)


# --- armctl.toml's top level --------------------------------------------------------------------
# Each key's shape is checked here, once, for every command (a misspelt `prot = …` must not
# quietly select the simulator); the tables' contents are checked by their owners: [profile]
# above, [lint] by armctl/lint/command.py, [jog] by armctl/jog/settings.py and keymap.py.


def _config_port(value) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _Bad('must be a device path or URL such as "/dev/ttyUSB0" or "sim://" '
                   "(leave port out to use the built-in simulator)")
    return value


def _config_baud(value) -> int:
    low, high = BAUD_RANGE
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise _Bad(f"must be a whole number of bit/s from {low} to {high}")
    return value


def _config_profile(value):
    if not isinstance(value, dict) and not (isinstance(value, str) and value.strip() and "\0" not in value):
        raise _Bad("must be a table ([profile]) or a path string (without a NUL character)")
    return value


def _config_table(value) -> dict:
    if not isinstance(value, dict):
        raise _Bad("must be a table")
    return value


CONFIG_SCHEMA: dict[str, Callable] = {
    "port": _config_port, "baud": _config_baud, "profile": _config_profile, "lint": _config_table, "jog": _config_table,
    "connector": _config_table,
}


def check_config_value(path, key: str, value):
    """``value`` of armctl.toml's top-level ``key``, checked; ConfigError naming the file and key."""
    rule = CONFIG_SCHEMA.get(key)
    if rule is None:
        raise ConfigError(f"{path}: unknown key {key!r}{unknown_key_hint(key, CONFIG_SCHEMA)}")
    try:
        return rule(value)
    except _Bad as bad:
        shown = f"[{key}]" if isinstance(value, dict) else f"{key} = {_short_repr(value)}"
        raise ConfigError(f"{path}: {shown} {bad}") from None


def _short_repr(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def load_profile(path: Path | str | None = None, start: Path | None = None) -> Profile:
    """The profile to use: ``path`` if given, else the one the project or user armctl.toml
    names (a path relative to that file), else the default; in every case with armctl.toml's
    top-level ``[connector]`` laid over it if that names no arm (``with_file_connector``).  The
    ``[connector]`` of the arm on a port — what ``armctl probe`` kept with it, a table measured
    on it — is ``armctl.calibration.arm_profile``'s, which the commands and the API use."""
    config = load_config(start)
    return with_file_connector(chosen_profile(path, config=config), config)


def chosen_profile(path: Path | str | None = None, start: Path | None = None, config: Config | None = None) -> Profile:
    """The profile alone, no ``[connector]`` of armctl.toml laid over it: a simulated arm's own (it
    takes its connector from its options)."""
    return _chosen_profile(path, load_config(start) if config is None else config)


def with_file_connector(profile: Profile, config: Config,
                        on_arm: Callable[[str, str], bool] = lambda measured_on, where: False) -> Profile:
    """``profile`` with armctl.toml's top-level ``[connector]`` laid over it, key by key, if it names
    no arm (a table written by hand: it applies on every port) or ``on_arm(measured_on, file)``
    says its ``measured_on`` is the arm in use (``armctl probe --write`` names it).  The table is
    checked either way."""
    table = config.values.get("connector")
    if table is None:
        return profile
    where = str(config.path_of("connector"))
    values, measured_on = connector_table(table, where)
    if measured_on is None or on_arm(measured_on, where):
        profile = with_connector(profile, values, where)
    return profile


def connector_table(table: dict, where: str) -> tuple[dict, str | None]:
    """armctl.toml's top-level ``[connector]``: its settings (checked, whether or not they apply
    to the arm in use) and the arm it was ``measured_on`` (None: it names none)."""
    values = {key: value for key, value in table.items() if key != MEASURED_ON}
    measured_on = table.get(MEASURED_ON)
    if MEASURED_ON in table and (not isinstance(measured_on, str) or not measured_on.strip()):
        raise ConfigError(f"{where}: connector.{MEASURED_ON} must be the port (or arm) the values were measured on, "
                          f"such as \"sim://?fifo_frames=50\" or \"usb 0403:6001 serial A10K4XYZ\"")
    _check({"connector": values}, where)
    return values, measured_on


def _chosen_profile(path: Path | str | None, config: Config) -> Profile:
    if path is not None:
        return parse_profile(read_toml(Path(path)), str(path))
    if "profile" not in config.values:
        return default_profile()
    entry = config.values["profile"]  # read_config checked it: a table or a path string
    config_path = config.path_of("profile")
    if isinstance(entry, dict):
        return parse_profile(entry, str(config_path), prefix="profile.")
    target = config_path.parent / entry
    return parse_profile(read_toml(target), str(target))
