"""armctl.toml: finding the project and user files, reading them, and checking their top-level keys.

Strategy: ``load_config`` lays the nearest project armctl.toml (``find_config``, walking up from
the working directory) over the user's (``user_config_path``), key by key at the top level;
each top-level key's shape is checked once by ``CONFIG_SCHEMA`` (``check_config_value``), so a
misspelt key is an error naming the file, never a silent default.  The tables' contents are
checked by their owners.  (``armctl config``, armctl/ui/config.py, prints what this finds.)
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..errors import ConfigError, ProfileError
from ..core.limits import BAUD_RANGE
from ..core.profile_schema import BadValue, unknown_key_hint
from ..core.toml_reading import parse_toml, short_repr

CONFIG_NAME = "armctl.toml"

def read_config(path: Path) -> dict:
    """An armctl.toml's whole content with every top-level key checked: the one reading of a
    project file and of the user file."""
    data = read_toml(path)
    for key, value in data.items():
        check_config_value(path, key, value)
    return data


def read_toml(path: Path) -> dict:
    """A TOML file as a dict; every failure is a ProfileError naming the file."""
    from .inputs import MAX_TOML_BYTES, UnusableInput, read_file_bounded

    try:
        data = read_file_bounded(str(path), str(path), MAX_TOML_BYTES)  # /dev/zero is not a profile
    except FileNotFoundError:
        if os.path.islink(path):  # (a config linked to a file since moved: `ls` shows it, so say what it is)
            raise ProfileError(f"{path}: a symbolic link to {os.readlink(path)}, which does not exist") from None
        raise ProfileError(f"{path}: file not found") from None
    except OSError as error:
        raise ProfileError(f"{path}: cannot read: {error.strerror or error}") from None
    except UnusableInput as error:  # too long, or a named pipe, device or directory
        raise ProfileError(str(error)) from None
    return parse_toml(data, str(path))


def find_config(start: Path | None = None) -> tuple[Path | None, dict]:
    """The first armctl.toml in ``start`` (default: the working directory) or a parent, and
    its whole content with every top-level key checked; ``(None, {})`` when there is none.
    Anything by that name is the file (``_present``): one that cannot be read is an error, never
    passed over for a parent's."""
    directory = Path.cwd() if start is None else Path(start)
    directory = directory.resolve()
    for candidate in (directory, *directory.parents):
        path = candidate / CONFIG_NAME
        if _present(path):
            return path, read_config(path)
    return None, {}


def _present(path: Path) -> bool:
    """Something is at ``path``: a file, or what ``read_toml`` refuses by name (a directory, a
    named pipe, a device, a dangling or looping symbolic link), not a quiet absence."""
    return os.path.lexists(path)


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
    user = read_config(user_path) if _present(user_path) else {}
    origins = {key: user_path for key in user}
    origins.update({key: project_path for key in project})
    return Config({**user, **project}, origins, project_path, user_path)


# --- armctl.toml's top level --------------------------------------------------------------------
# Each key's shape is checked here, once, for every command (a misspelt `prot = …` must not
# quietly select the simulator); the tables' contents are checked by their owners: [profile]
# above, [lint] by armctl/lint/command.py, [jog] by armctl/jog/settings.py and keymap.py.


def _config_port(value) -> str:
    if not isinstance(value, str) or not value.strip() or "\0" in value:  # (a NUL: TOML holds one, no port name does)
        raise BadValue('must be a device path or URL such as "/dev/ttyUSB0" or "sim://", without a NUL character '
                   "(leave port out to use the built-in simulator)")
    return value


def _config_baud(value) -> int:
    low, high = BAUD_RANGE
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise BadValue(f"must be a whole number of bit/s from {low} to {high}")
    return value


def _config_profile(value):
    if not isinstance(value, dict) and not (isinstance(value, str) and value.strip() and "\0" not in value):
        raise BadValue("must be a table ([profile]) or a path string (without a NUL character)")
    return value


def _config_table(value) -> dict:
    if not isinstance(value, dict):
        raise BadValue("must be a table")
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
    except BadValue as bad:
        shown = f"[{key}]" if isinstance(value, dict) else f"{key} = {short_repr(value)}"
        raise ConfigError(f"{path}: {shown} {bad}") from None
