"""Building a profile: checked values laid over the packaged default, built into frozen dataclasses and cross-checked.

Strategy: ``parse_profile`` checks the given data (armctl/core/profile_schema.py), lays it over the
packaged default (``armctl/data/default_profile.toml``) section by section, records where each
key came from (``_sources``), builds the dataclasses of armctl/core/profile_model.py and
cross-checks them (fixed poses inside the joint limits, gripper values inside the PWM range).
``default_profile`` is the packaged default alone.  Pure apart from reading the packaged file.
"""

from __future__ import annotations

import dataclasses
import functools
import pkgutil

from ..errors import ProfileError
from .kinematics import JOINT_COUNT, Links
from .profile_model import (
    CONNECTOR_KEYS, DOCUMENT, FIXED_POSES, ILLUSTRATIVE, PROTOCOL, PROTOCOL_KEYS, Connector, LintOptions, Profile, Pwm,
    Speeds, Timing, Workspace,
)
from .profile_schema import _OPTIONAL_SECTIONS, PROFILE_SCHEMA, _apply, _unknown, check_profile_data
from .toml_reading import parse_toml

DEFAULT_RESOURCE = ("armctl.data", "default_profile.toml")

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
    for section, rule in PROFILE_SCHEMA.items():
        for key in ([f"{section}.{k}" for k in rule] if isinstance(rule, dict) else [section]):
            sources[key] = DOCUMENT if section == "connector" else PROTOCOL if key in PROTOCOL_KEYS else ILLUSTRATIVE
    for section, content in given.items():
        for key in ([f"{section}.{k}" for k in content] if isinstance(content, dict) else [section]):
            sources[key] = source
    return sources


def _build(data: dict, source: str, prefix: str, sources: dict[str, str]) -> Profile:
    for section in PROFILE_SCHEMA:
        if isinstance(PROFILE_SCHEMA[section], dict) and section not in _OPTIONAL_SECTIONS:
            missing = [k for k in PROFILE_SCHEMA[section] if k not in data.get(section, {})]
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


# What the arm does that the profile keeps outside [connector], measured and kept with the
# [connector] values all the same: ``armctl probe`` stores them with the arm, and ``--write`` puts
# them into armctl.toml's [connector] (its one table that names the arm: it has no [timing]).
MEASURED_ELSEWHERE = {"command_overhead_s": "timing"}


def check_connector_table(table: dict, source: str) -> dict[str, dict]:
    """armctl.toml's top-level ``[connector]`` ``table`` checked, by the profile section each key
    lands in (``{"connector": …, "timing": …}``); errors name ``connector.KEY``."""
    known = [*PROFILE_SCHEMA["connector"], *MEASURED_ELSEWHERE]  # (what an unknown key is told: all it takes)
    for key in table:
        if key not in known:
            raise _unknown(source, f"connector.{key}", known)
    elsewhere = {key: value for key, value in table.items() if key in MEASURED_ELSEWHERE}
    checked = {"connector": check_profile_data({"connector": {k: v for k, v in table.items() if k not in elsewhere}},
                                               source)["connector"], "timing": {}}
    for key, value in elsewhere.items():
        section = MEASURED_ELSEWHERE[key]
        checked[section][key] = _apply(PROFILE_SCHEMA[section][key], value, source, f"connector.{key}")
    return checked


def with_connector(profile: Profile, table: dict, source: str) -> Profile:
    """``profile`` with armctl.toml's top-level ``[connector]`` ``table`` laid over its own, key by
    key (checked here; errors name ``source`` and ``connector.KEY``); a key of ``MEASURED_ELSEWHERE``
    lands in its own section."""
    checked = check_connector_table(table, source)
    given, timing = checked["connector"], checked["timing"]
    if not given and not timing:
        return profile
    sources = {**profile.sources, **{f"connector.{key}": source for key in given},
               **{f"timing.{key}": source for key in timing}}
    values = {key: getattr(profile.connector, key) for key in CONNECTOR_KEYS} | given
    return dataclasses.replace(profile, connector=_connector(values, sources),
                               timing=dataclasses.replace(profile.timing, **timing), sources=sources)


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
def default_profile_data() -> dict:
    package, name = DEFAULT_RESOURCE
    # pkgutil, not importlib.resources: the same bytes from a folder or a zip, without importing
    # tempfile, shutil and the compression modules at every start (issue 13: start-up)
    text = pkgutil.get_data(package, name)
    source = f"<packaged {name}>"
    return check_profile_data(parse_toml(text, source), source)


def parse_profile(data: dict, source: str = "<profile>", prefix: str = "") -> Profile:
    """A profile from a TOML-shaped dict laid over the packaged default.

    ``prefix`` is prepended to key names in messages (``"profile."`` for an armctl.toml table).
    """
    given = check_profile_data(data, source, prefix)
    return _build(_merge(default_profile_data(), given), source, prefix, _sources(given, source))


@functools.lru_cache(maxsize=1)
def default_profile() -> Profile:
    """The packaged default profile (every number illustrative)."""
    package, name = DEFAULT_RESOURCE
    return _build(default_profile_data(), f"<packaged {name}>", "", _sources({}, ""))
