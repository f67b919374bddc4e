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
the profile's own table, then what ``armctl probe`` kept with that arm (armctl/host/calibration.py),
then armctl.toml's top-level table if it names no arm or its ``measured_on`` is that arm.

This module chooses and loads the profile and is the façade of its parts, each importing only
downwards: armctl/core/toml_reading.py (one TOML document, bounded), armctl/core/profile_model.py (the
frozen dataclasses and provenance), armctl/core/profile_schema.py (the schema and its checking),
armctl/core/profile_build.py (laying over the packaged default, building, cross-checking) and
armctl/host/config_file.py (finding and reading armctl.toml, its top-level keys).  Callers import
every name from here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from .config_file import (  # noqa: F401 - the façade offers every part's names
    CONFIG_NAME, CONFIG_SCHEMA, Config, check_config_value, find_config, load_config, read_config, user_config_path,
)
from ..errors import ConfigError, ProfileError  # noqa: F401 - ProfileError: callers catch it from here
from ..core.profile_build import (  # noqa: F401
    DEFAULT_RESOURCE, check_connector_table, default_profile, default_profile_data, parse_profile, with_connector,
)
from ..core.profile_model import (  # noqa: F401
    CONNECTOR_KEYS, CONTROL_FRAMES, DOCUMENT, FIXED_POSES, GRIPPER_STATES, ILLUSTRATIVE, MEASURED_ON, PROBE, PROTOCOL,
    PROTOCOL_KEYS, SPEED_TOLERANCE_RANGE, STATUS_XYZ_FRAMES, Connector, LintOptions, Profile, Pwm, Speeds, Timing,
    Workspace,
)
from ..core.profile_schema import MIN_TIME_S, PROFILE_SCHEMA, check_profile_data, unknown_key_hint  # noqa: F401
from .config_file import read_toml  # noqa: F401
from ..core.toml_reading import MAX_TOML_DEPTH, TOML_INT_RANGE  # noqa: F401


def load_profile(path: Path | str | None = None, start: Path | None = None) -> Profile:
    """The profile to use: ``path`` if given, else the one the project or user armctl.toml
    names (a path relative to that file), else the default; in every case with armctl.toml's
    top-level ``[connector]`` laid over it if that names no arm (``with_file_connector``).  The
    ``[connector]`` of the arm on a port — what ``armctl probe`` kept with it, a table measured
    on it — is ``armctl.host.calibration.arm_profile``'s, which the commands and the API use."""
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
    check_connector_table(values, where)
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
